# Thin front door: every real rule lives in CMake. See README.md.
BUILD ?= build
JOBS  ?= 2
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps configure build demo test bench clean

all: build

deps:
	@bash tools/deps.sh

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS)

build: configure
	@cmake --build $(BUILD) -j$(JOBS)

# The demo builds only what it runs (pikg-gen kernels + the N-body example).
demo: configure
	@cmake --build $(BUILD) -j$(JOBS) --target pik_demo_run

test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

bench: build
	@cmake --build $(BUILD) -j$(JOBS) --target pik_benchmarks
	@bash bench/run_all.sh $(BUILD)

clean:
	@rm -rf $(BUILD)
