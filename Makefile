# Entry points for people and CI. Every target first installs what is missing (Debian
# packages, see scripts/install-deps.sh), so each works on a fresh clone of a fresh machine.
#
#   make demo   simulate two runs of the lab (two lights), teach the firmware on one, repeat
#               on the other, score it against the ground truth (scripts/demo.sh)
#   make demo-corridor  the localiser on the bundled corridor images (Milford 2013)
#   make test   build host (plain, ASan/UBSan), target (RV32IMC, QEMU) and fuzz; run all tests
#   make bench  run the benchmark images under QEMU -> build/bench/summary.json (+ mapping/, board/)
#   make board-route  teach and repeat the ~1 km route on the emulated board (~25 min)
#   make tools  build the host tools into build/host/bin
#   make bench-eval  time seqslam eval on 3600 x 3600 and 30000 x 30000 places (scripts/bench-eval.sh)
#   make tune-eval  seqslam tune on the real pairs and simulated light pairs, each held out in turn
#   make route-eval  the board's route search against the full search, simulated pairs (6-15 min)
#   make confidence-eval  which confidence offset ranks best: online, batch, fixed (~15 s + sims)
#   make perspective  head roll / shift tolerance tables, ~75 min (scripts/perspective.sh)
#   make fuzz   fuzz the parsers and loaders for FUZZ_SECONDS (default 300) or FUZZ_RUNS each
.DEFAULT_GOAL := help
JOBS ?= $(shell nproc 2>/dev/null || echo 2)

FUZZ_SECONDS ?= 300
FUZZ_RUNS ?=

.PHONY: help deps tools demo demo-corridor bench-eval tune-eval route-eval confidence-eval board-route perspective test test-host test-asan test-target test-fuzz fuzz bench format tidy clean

help:
	@sed -n '1,16p' Makefile | sed 's/^# \{0,1\}//'

deps:
	@scripts/install-deps.sh

tools: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS)

demo: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS) --target seqslam-sim seqslam-cli seqslam-firmware
	scripts/demo.sh

demo-corridor: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS) --target seqslam-demo
	build/host/bin/seqslam-demo

test: test-host test-asan test-target test-fuzz
	@echo "make test: all suites passed (host, host-asan, target, fuzz)"

test-host: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS)
	ctest --preset host -j $(JOBS)

test-asan: deps
	cmake --preset host-asan
	cmake --build --preset host-asan -j $(JOBS)
	ctest --preset host-asan -j $(JOBS)

test-target: deps
	cmake --preset target
	cmake --build --preset target -j $(JOBS)
	ctest --preset target -j $(JOBS)

# Brief, deterministic fuzzing (fixed seed and run count) from the seed corpus.
test-fuzz: deps
	cmake --preset fuzz
	cmake --build --preset fuzz -j $(JOBS)
	ctest --preset fuzz

fuzz: test-fuzz
	FUZZ_SECONDS=$(FUZZ_SECONDS) FUZZ_RUNS=$(FUZZ_RUNS) scripts/fuzz.sh

bench-eval: tools
	scripts/bench-eval.sh

# seqslam tune (leave-one-pair-out) on every real pair (corridor, Gardens Point) and the light
# pairs of seeds 1-3, by smoothed AUC with each dataset weighing the same -> build/tune-eval/
# (docs/accuracy.md).
tune-eval: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS) --target seqslam-cli seqslam-sim
	scripts/tune-eval.sh

# The route search against the full search on the simulator's lights, kidnapped and jump
# scenarios, seeds 1-3 (cached in build/route-eval/sim) -> build/route-eval/summary.json
# (docs/accuracy.md).
route-eval: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS) --target seqslam-cli seqslam-sim
	scripts/route-eval.sh

# The double reference's recall at 100 % precision under the online, batch and fixed offsets
# of the confidence, corridor and light pairs of seeds 1-3 -> build/confidence-eval/summary.md
# (docs/normalisation.md).
confidence-eval: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS) --target seqslam-cli seqslam-sim
	scripts/confidence-eval.sh

perspective: tools
	scripts/perspective.sh

# Three images (docs/performance.md): localisation kernels -> build/bench, mapping ->
# build/bench/mapping, the head board's localiser on a card -> build/bench/board; then the
# board's figures and the board image's size per module (scripts/size-report.py) are merged
# into build/bench/summary.json.
bench: deps
	cmake --preset target
	cmake --build --preset target -j $(JOBS) --target seqslam_bench seqslam_bench_mapping \
	  seqslam_bench_board seqslam_fw_app
	scripts/run-bench.sh build/target/firmware/seqslam_bench.elf build/bench
	@echo
	scripts/run-bench.sh build/target/firmware/seqslam_bench_mapping.elf build/bench/mapping
	@echo
	scripts/run-bench.sh build/target/firmware/seqslam_bench_board.elf build/bench/board
	@echo
	scripts/size-report.py --json build/bench/board/size.json build/target/firmware/seqslam_fw_app.elf
	scripts/bench-summary.py build/bench/summary.json build/bench/board/summary.json \
	  build/bench/board/size.json

# The ~1 km route (seqslam-sim --scenario route, ~5 000 places a run) taught and repeated on the
# emulated board and on the PC build, compared byte for byte (scripts/board-teach-repeat.sh)
# -> build/board-route/summary.txt (docs/firmware.md). The repeat streams the scan's 1 024 places
# a place on QEMU (~17 min): the emulator's time limit is raised to an hour.
board-route: deps
	cmake --preset host
	cmake --build --preset host -j $(JOBS) --target seqslam-cli seqslam-sim seqslam-firmware
	cmake --preset target
	cmake --build --preset target -j $(JOBS) --target seqslam_fw_app
	SEQSLAM_QEMU_TIMEOUT=$${SEQSLAM_QEMU_TIMEOUT:-3600} scripts/board-teach-repeat.sh \
	  --scenario route --work build/board-route --host-bin build/host/bin \
	  --board build/target/firmware/seqslam_fw_app.elf

format:
	clang-format -i $$(git ls-files '*.h' '*.cpp')

tidy: tools
	clang-tidy -p build/host $$(git ls-files 'src/*.cpp')

clean:
	rm -rf build
