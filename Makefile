# contactbench — the two commands a user needs are `make demo` and `make test`.
SHELL := /bin/bash
BUILD ?= build
JOBS ?= $(shell nproc)
PY := /usr/bin/python3
CB := $(BUILD)/bin/contactbench
CB_CACHE ?= $(HOME)/.cache/contactbench
DATA ?= $(abspath ../shared/paper-data)
export OPENBLAS_NUM_THREADS ?= 1
export MPLBACKEND ?= Agg

DEB_PACKAGES := build-essential cmake git zlib1g-dev libeigen3-dev libsuitesparse-dev nlohmann-json3-dev \
  libgtest-dev libbenchmark-dev libopenblas0-pthread \
  python3-numpy python3-pandas python3-matplotlib python3-scipy libcgal-demo

.PHONY: help deps build test demo bench baseline reproduce stress fuzz clean meshes

help:
	@echo "make demo       install, build, simulate a small scene, run the solvers, write figures"
	@echo "make test       install, build from scratch (Release), run every C++ and Python test + CI perf gate"
	@echo "make deps       install the Debian packages (apt-get, as root); quick when present"
	@echo "make build      configure and build into $(BUILD)/"
	@echo "make bench      Google Benchmark suite (JSON in results/bench/)"
	@echo "make baseline   rewrite results/baselines/ci from the CI suite (after an intended change)"
	@echo "make reproduce  the paper's figures and report in results/paper/ (QUICK=1: < 5 min)"
	@echo "make stress     the stress suite and its stability table in results/stress/"
	@echo "make fuzz       fuzz the snapshot, suite and scene readers (FUZZ_SECONDS=60 each)"

deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" != 0 ]; then \
	    echo "make deps: missing Debian packages:$$missing"; \
	    echo "run as root: apt-get update && apt-get install -y$$missing"; exit 1; \
	  fi; \
	  echo "make deps: installing$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null || exit 1; \
	else echo "make deps: all Debian packages present"; fi
	@$(MAKE) --no-print-directory meshes

# Surface meshes of the classic models, unpacked from Debian's libcgal-demo into a cache.
meshes:
	@if [ ! -f "$(CB_CACHE)/meshes/bunny00.off" ]; then \
	  mkdir -p "$(CB_CACHE)/meshes" && \
	  tar -xzf /usr/share/doc/libcgal-dev/data.tar.gz -C "$(CB_CACHE)" --wildcards '*/meshes/*.off' \
	    --transform='s,.*/meshes/,meshes/,' && echo "meshes: unpacked CGAL data into $(CB_CACHE)/meshes"; \
	fi

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

test: deps
	rm -rf $(BUILD)
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j $(JOBS)
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 600
	@if [ -f suites/ci.json ]; then $(MAKE) --no-print-directory ci-perf; fi

# CI performance gate: the fixed CI suite against the committed baseline (counters exact).
ci-perf:
	rm -rf results/ci-new
	$(CB) run suites/ci.json --out results/ci-new
	$(CB) compare results/baselines/ci results/ci-new

baseline: build
	rm -rf results/baselines/ci.tmp
	$(CB) run suites/ci.json --out results/baselines/ci.tmp
	rm -rf results/baselines/ci && mv results/baselines/ci.tmp results/baselines/ci
	@echo "baseline: rewrote results/baselines/ci (commit it with the change that explains it)"

demo: deps build
	$(CB) simulate scenes/demo.json --out results/demo/sim
	$(CB) run suites/demo.json --out results/demo
	$(PY) plots/convergence.py results/demo
	$(PY) plots/profiles.py results/demo
	$(PY) plots/reproduce.py --contactbench $(CB) --data $(DATA) --out results/paper --quick
	@echo "demo: simulation pictures in results/demo/sim/, solver figures and profiles in results/demo/figures/,"
	@echo "      the paper's figures and claims (quick mode) in results/paper/report.md"

bench: build
	mkdir -p results/bench
	$(BUILD)/bin/cb_bench --benchmark_out=results/bench/bench.json --benchmark_out_format=json

reproduce: deps build
	$(PY) plots/reproduce.py --contactbench $(CB) --data $(DATA) --out results/paper $(if $(QUICK),--quick,)

stress: build
	$(CB) stress --out results/stress
	$(PY) plots/stability.py results/stress

# Each reader on its own corpus: FUZZ_SECONDS per target (FUZZ_TARGETS to pick some).
FUZZ_TARGETS ?= qpsnap suite scene
fuzz: deps
	cmake -S . -B $(BUILD)-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCB_FUZZ=ON \
	  -DCB_BUILD_TESTS=OFF -DCB_BUILD_BENCH=OFF
	cmake --build $(BUILD)-fuzz -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	for t in $(FUZZ_TARGETS); do \
	  corpus=tests/fuzz/corpus; [ $$t = qpsnap ] || corpus=tests/fuzz/corpus_$$t; \
	  mkdir -p $(BUILD)-fuzz/corpus_$$t && cp $$corpus/* $(BUILD)-fuzz/corpus_$$t/ && \
	  $(BUILD)-fuzz/bin/fuzz_$$t -max_total_time=$(or $(FUZZ_SECONDS),60) -timeout=10 -rss_limit_mb=2048 \
	    -artifact_prefix=$(BUILD)-fuzz/$$t- $(BUILD)-fuzz/corpus_$$t || exit 1; \
	done

clean:
	rm -rf $(BUILD) $(BUILD)-*
