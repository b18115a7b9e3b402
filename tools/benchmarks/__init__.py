"""The measurements behind ``python -m tools.bench <command>``: one module per command, each
with ``HELP``, ``add_arguments(parser)`` and ``run(args)`` (returns the exit status)."""
