# cellsim: every target installs the system packages it needs (apt-get, with sudo when
# not root) before building. The two quick-start commands are `make paper` and `make test`.

# libopenblas0-pthread: the BLAS behind UMFPACK's fronts in the 3-D runs (the reference
# BLAS that libsuitesparse-dev would otherwise bring is several times slower).
APT_PACKAGES := libsundials-dev libsuitesparse-dev libclang-dev pkg-config \
                libfontconfig1-dev libfreetype-dev fonts-dejavu-core gmsh libopenblas0-pthread
CARGO ?= cargo
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: all deps build paper fidelity test memcheck test-cluster robertson bench lint clean

all: build

# Install the missing Debian/Ubuntu packages (only those not already installed).
deps:
	@command -v $(CARGO) >/dev/null || { echo "cargo not found: install Rust from https://rustup.rs"; exit 1; }
	@missing=""; for p in $(APT_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

build: deps
	$(CARGO) build --release

# The main job: the paper's scenes, plots written to plots/.
paper: deps
	$(CARGO) run --release -- paper --out plots

# The ambiguity table: every reading of the paper on every scene (docs/paper-fidelity.md).
fidelity: deps
	$(CARGO) run --release -- sweep cases/sweeps/paper-fidelity.ron --out plots/sweeps/paper-fidelity --jobs 2

# All tests (release mode: the finite-element tests are numeric). One OpenBLAS thread: the
# test threads already fill the cores, and OpenBLAS's second thread, spinning while it
# waits, took a core from the test beside it (the coarse 3-D tests factorize as fast with
# one: 71.8 s wall either way, 110 against 72 s of CPU).
test: deps
	OPENBLAS_NUM_THREADS=1 $(CARGO) test --release

# valgrind memcheck of short cell-model runs with each sparse LU (installs valgrind).
memcheck: deps
	scripts/memcheck.sh

# `cellsim sweep --slurm --submit` on a real Slurm: a single-node cluster started on this
# machine (installs slurm-wlm and munge), its result compared with the same sweep run locally.
test-cluster: deps
	scripts/slurm-test.sh

robertson: deps
	$(CARGO) run --release --example robertson

bench: deps
	$(CARGO) bench --features bench

lint: deps
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --release --all-targets --features bench -- -D warnings

clean:
	$(CARGO) clean
