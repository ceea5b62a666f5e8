# pliant — the two commands a newcomer needs:
#   make demo   install dependencies, configure, build, run `pliant demo` (outputs in out/demo)
#   make test   install dependencies, configure, build, run every test with ctest
# Other targets: build, bench, format, clean. Set PLIANT_SKIP_DEPS=1 to skip the package check.

BUILD_DIR ?= build/release
OUT_DIR ?= out/demo
JOBS ?= 2
CMAKE_ARGS ?=
PLIANT := $(BUILD_DIR)/bin/pliant

.DEFAULT_GOAL := help
.PHONY: help deps configure build demo demo-photos test bench format clean

help:
	@echo "make demo    install deps, build (Release, $(BUILD_DIR)), run the demo into $(OUT_DIR)"
	@echo "make demo-photos  only the demo's photo path (COLMAP): photos -> poses -> field -> object"
	@echo "make test    install deps, build, run all tests (ctest)"
	@echo "make build   install deps, configure and build everything (no tests run)"
	@echo "make bench   build, then run '$(PLIANT) bench bvh'"
	@echo "make format  clang-format every C++ source in place (scripts/check-format --fix)"
	@echo "make clean   remove build/ and out/"

deps:
	scripts/install-deps

# cmake re-runs itself when CMakeLists change, so the tree is configured only once. The demo and
# the tests build for this machine's CPU (PLIANT_NATIVE), as docs/performance.md measures.
configure: deps
	@if [ ! -f $(BUILD_DIR)/CMakeCache.txt ]; then \
	    cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release -DPLIANT_NATIVE=ON $(CMAKE_ARGS); \
	fi

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

# The demo needs only the CLI: build that target, not the tests and benchmarks.
demo: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target pliant
	$(PLIANT) demo --out $(OUT_DIR)
	scripts/demo-photos $(PLIANT) $(OUT_DIR)/photos
	@echo "make demo: outputs in $(OUT_DIR)/ (folded_sheet.ply, folded_sheet_t1.ply; drape/, twist/, pile/, flag/, garment/: preview.mp4 (watch these), frames/*.obj, stats.json (garment/: also cloth.pc2); untangle/: preview.mp4 (the drape untangled after falling through itself), fall/preview.mp4, crossing/preview.mp4 (two sheets crossing, untangled); volume/: volume.png, turntable.mp4; deform/: twist.mp4; nerf/: compare.png, twist.mp4; summary.json; photos/: compare.png (held-out photos above the reconstruction), object.png (the cropped object), twist.mp4 (it twisted))"

# From photos (data/capture, COLMAP poses) to the object's RGBA volume; skipped without COLMAP.
demo-photos: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target pliant
	scripts/demo-photos $(PLIANT) $(OUT_DIR)/photos

test: build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j$(JOBS)

bench: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target pliant
	$(PLIANT) bench bvh

format:
	scripts/check-format --fix

clean:
	rm -rf build out
