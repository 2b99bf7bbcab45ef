# Thin wrapper over the CMake presets. The two commands the README names first:
#   make demo   installs what is missing, builds, and runs the main job (the thesis' tetcli example), the bunny scene and the hand fist,
#               each with its browser report (index.html)
#   make test   installs what is missing, builds, and runs every test
#   make docs   installs what is missing and builds the documentation site (docs/, mkdocs.yml) into build/site
#   make gallery  builds, then remakes docs/gallery.md and its pictures (scripts/gallery.sh: runs and renders)
PRESET ?= release
JOBS   ?= $(shell nproc)
BUILD  := build/$(PRESET)

.PHONY: all deps configure build demo test bench docs gallery clean

all: build

deps:
	bash scripts/install-deps

# A build directory made before the presets used Ninja (Unix Makefiles) cannot be reconfigured: it is remade.
configure: deps
	@if [ -f $(BUILD)/CMakeCache.txt ] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$$' $(BUILD)/CMakeCache.txt; then \
	  echo "make: $(BUILD) was made by another CMake generator; removing it to configure with Ninja"; rm -rf $(BUILD); fi
	cmake --preset $(PRESET)

build: configure
	cmake --build --preset $(PRESET) -j $(JOBS)

demo: build
	$(BUILD)/apps/tetcli 10 stable_neo_hookean 1.0 10.0 output/stretch
	$(BUILD)/apps/snh run scenes/bunny_squash.json --out output/bunny_squash
	$(BUILD)/apps/snh run scenes/hand_fist.json --out output/hand_fist
	@echo "demo output: $(CURDIR)/output/stretch (the stretch test: frames 000.obj ... 025.obj, 000.vtu ... 025.vtu + frames.pvd for ParaView, stats.json, stats.csv)"
	@echo "             $(CURDIR)/output/bunny_squash (the bunny squashed and released: the same files)"
	@echo "             $(CURDIR)/output/hand_fist (the hand's flesh closing into a fist: surface/ and lbs/ OBJ frames, flesh.usda)"
	@echo "open in a browser: $(CURDIR)/output/stretch/index.html"
	@echo "                   $(CURDIR)/output/bunny_squash/index.html"
	@echo "                   $(CURDIR)/output/hand_fist/index.html"

test: build
	ctest --preset $(PRESET)

bench: build
	$(BUILD)/bench/bench_material --benchmark_min_time=0.2

# Strict: a broken link, or a page missing from the nav, fails the build.
docs: deps
	mkdocs build --strict --config-file mkdocs.yml --site-dir build/site
	@echo "docs: open $(CURDIR)/build/site/index.html in a browser"

gallery: build
	bash scripts/gallery.sh

clean:
	rm -rf build
