# Penumbra developer commands. See README.md.
LINES ?= 5.2 4.5
DEMO_LINE ?= 5.2
PYTEST_ARGS ?=

.PHONY: demo test setup bench zip clean

setup:
	@for l in $(LINES); do tools/setup.sh $$l || exit 1; done

# Render the demo scene: out/demo.png (display-referred) and out/demo.exr (scene linear).
demo:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python tools/demo.py --out out

# The test suite on every supported Blender line (each in its own venv and process).
test:
	@status=0; for l in $(LINES); do \
	  tools/setup.sh $$l || exit 1; \
	  echo "== Blender $$l =="; \
	  .venv/blender-$$l/bin/python -m pytest -q tests $(PYTEST_ARGS) || status=1; \
	done; exit $$status

bench:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python tools/benchmark.py --out out

# Build the extension zip with Blender's own tool.
zip:
	tools/setup.sh $(DEMO_LINE)
	.venv/blender-$(DEMO_LINE)/bin/python tools/build_extension.py --out out

clean:
	rm -rf out build .pytest_cache
