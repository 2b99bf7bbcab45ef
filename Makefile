# Thin wrapper over the CMake presets. The two commands the README names first:
#   make demo   installs what is missing, builds, and runs the main job
#   make test   installs what is missing, builds, and runs every test
PRESET ?= release
JOBS   ?= $(shell nproc)
BUILD  := build/$(PRESET)

.PHONY: all deps configure build demo test bench clean

all: build

deps:
	bash scripts/install-deps

configure: deps
	cmake --preset $(PRESET)

build: configure
	cmake --build --preset $(PRESET) -j $(JOBS)

demo: build
	$(BUILD)/apps/snh material --stability

test: build
	ctest --preset $(PRESET)

bench: build
	$(BUILD)/bench/bench_material --benchmark_min_time=0.2

clean:
	rm -rf build
