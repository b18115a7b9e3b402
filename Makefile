# Penumbra developer commands. See README.md. Tools run as modules from the repository root
# (python -m tools.<name>), so the dev library devkit/ is importable.
LINES ?= 5.2 4.5
DEMO_LINE ?= 5.2
PYTEST_ARGS ?=
# make bench                                   frame times of every engine on the demo scene
# make bench BENCH=perf ARGS=--quick           frame cost and scaling against Workbench
# make bench BENCH=post                        cost of each post layer
# make bench BENCH=shadows ARGS=--quick        shadow error against time (ARGS: that command's options)
# make bench BENCH=samples                     render samples: error against time, against Cycles and EEVEE
# make bench BENCH=soak                        process memory over 300 F12 renders
# make bench BENCH=assets ARGS=--quick         glTF assets (devkit/gltf/): error against Cycles, Penumbra vs EEVEE
# make bench BENCH=world ARGS=--quick          world light with visibility: error against time vs Cycles and EEVEE
BENCH ?= frame
ARGS ?=

.PHONY: demo test lint setup bench zip clean

setup:
	@for l in $(LINES); do tools/setup.sh $$l || exit 1; done

# Render the demo scene: out/demo.png (display-referred) and out/demo.exr (scene linear).
demo:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python -m tools.demo --out out

# Lint and format check (ruff, configured in ruff.toml) over the whole repository.
lint:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python -m ruff check .
	.venv/blender-$(DEMO_LINE)/bin/python -m ruff format --check .

# Lint, then the test suite on every supported Blender line (each in its own venv and process),
# each line ending with its ten slowest tests and its time.
test: lint
	@status=0; for l in $(LINES); do \
	  tools/setup.sh $$l || exit 1; \
	  echo "== Blender $$l =="; \
	  start=$$(date +%s); \
	  .venv/blender-$$l/bin/python -m pytest -q --durations=10 tests $(PYTEST_ARGS) || status=1; \
	  echo "== Blender $$l: $$(( $$(date +%s) - start )) s =="; \
	done; exit $$status

# Benchmarks: python -m tools.bench {frame,post,shadows} (see tools/bench.py).
bench:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python -m tools.bench $(BENCH) --out out $(ARGS)

# Build the extension zip with Blender's own tool.
zip:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python -m tools.build_extension --out out

clean:
	rm -rf out build .pytest_cache
