# grainkit - the only build. `make help` lists the targets.
#
# Every program under tests/, examples/, bench/ and tools/ is one C file that
# defines GK_IMPLEMENTATION itself, so each builds with a single compiler call.
# Variables you may override: CC, CXX, OPT, ARCH, OMP, PREFIX, BUILD.

CC      ?= cc
CXX     ?= c++
OPT     ?= -O2
ARCH    ?= -march=native
OMP     ?= -fopenmp
BUILD   ?= build
PREFIX  ?= /usr/local

WARN    := -std=c99 -pedantic -Wall -Wextra -Werror
# determinism: no FMA contraction, never -ffast-math (DESIGN.md principle 3)
FPFLAGS := -ffp-contract=off -fno-fast-math
CFLAGS  := $(WARN) $(OPT) $(ARCH) $(FPFLAGS) $(OMP) -Iinclude -Itests
LDLIBS  := -lm

HEADERS  := $(wildcard include/gk_*.h)
TEST_SRC := $(wildcard tests/test_*.c)
EX_SRC   := $(wildcard examples/*.c)
BENCH_SRC:= $(filter-out bench/%_part.c,$(wildcard bench/*.c))
TOOL_SRC := $(wildcard tools/*.c)

TESTS    := $(patsubst tests/%.c,$(BUILD)/%,$(TEST_SRC))

# the optional MPI build (gk_twoscale.h with GK_TWOSCALE_MPI): `make mpi`; `make test` runs its tests
# with 2 ranks when mpicc is installed (Open MPI: openmpi-bin libopenmpi-dev) and says so when not
MPICC   ?= mpicc
MPIRUN  ?= mpirun
HAVE_MPI := $(shell command -v $(MPICC) >/dev/null 2>&1 && command -v $(MPIRUN) >/dev/null 2>&1 && echo yes)
# Open MPI refuses root without --allow-run-as-root, and more ranks than it counts cores without
# --oversubscribe (other MPIs do not know these flags)
MPIRUN_FLAGS ?= $(shell $(MPIRUN) --version 2>/dev/null | grep -q 'Open MPI' && \
                  { [ "$$(id -u)" = 0 ] && echo '--allow-run-as-root --oversubscribe' || echo '--oversubscribe'; })
MPI_TEST_SRC := $(wildcard tests/mpi_*.c)
MPI_TESTS    := $(patsubst tests/mpi_%.c,$(BUILD)/mpi/mpi_%,$(MPI_TEST_SRC))
MPI_RUNNERS  := $(patsubst tests/mpi_%.c,$(BUILD)/mpi/run_%,$(MPI_TEST_SRC))
MPI_PROGS    := $(MPI_TESTS) $(MPI_RUNNERS)
EXAMPLES := $(patsubst examples/%.c,$(BUILD)/%,$(EX_SRC))
BENCHES  := $(patsubst bench/%.c,$(BUILD)/bench_%,$(BENCH_SRC))
TOOLS    := $(patsubst tools/%.c,$(BUILD)/%,$(TOOL_SRC))

.PHONY: all mpi test check bench bench-peers run run-rve run-mpm run-footing run-collapse install uninstall format format-check clean help \
        check-headers check-asan check-nosimd tradeoff

all: $(TESTS) $(EXAMPLES) $(BENCHES) $(TOOLS)

help:
	@echo "make            build tests, examples, benchmarks and tools into $(BUILD)/"
	@echo "make run        the main job: FEMxDEM biaxial test (see README.md)"
	@echo "make run-rve    one RVE along a shear path"
	@echo "make run-mpm | run-footing | run-collapse   seed 003's MPMxDEM biaxial, footing, column collapse"
	@echo "make test       build and run every test; ends with 'N passed, N failed'"
	@echo "make mpi        the MPI programs (mpicc; gk_twoscale.h with GK_TWOSCALE_MPI) into $(BUILD)/mpi/"
	@echo "make check      tests under ASan+UBSan, a no-SIMD build, header portability"
	@echo "make bench      performance programs (2 cores)"
	@echo "make tradeoff   accuracy against cost of the drivers, the whole sweep (10-15 min; build/tradeoff/)"
	@echo "make bench-peers  the same workloads in LAMMPS / LIGGGHTS / YADE when installed"
	@echo "make install PREFIX=dir   headers + pkg-config file"
	@echo "make format / format-check   clang-format"

$(BUILD) $(BUILD)/asan $(BUILD)/nosimd $(BUILD)/hdr $(BUILD)/mpi:
	@mkdir -p $@

$(BUILD)/test_%: tests/test_%.c $(HEADERS) tests/gk_test.h | $(BUILD)
	$(CC) $(CFLAGS) -o $@ $< $(LDLIBS)

$(BUILD)/%: examples/%.c $(HEADERS) $(wildcard examples/*.h) | $(BUILD)
	$(CC) $(CFLAGS) -o $@ $< $(LDLIBS)

$(BUILD)/bench_%: bench/%.c $(HEADERS) $(wildcard bench/*_part.c bench/*.h) | $(BUILD)
	$(CC) $(CFLAGS) -Ibench -o $@ $< $(LDLIBS)

# one program, two copies of grainkit (double and float), all static
$(BUILD)/bench_dem_step: bench/dem_step.c bench/dem_step_part.c bench/dem_step.h $(HEADERS) | $(BUILD)
	$(CC) $(CFLAGS) -Ibench -c bench/dem_step_part.c -o $(BUILD)/dem_step_double.o
	$(CC) $(CFLAGS) -Ibench -DGK_REAL_FLOAT -c bench/dem_step_part.c -o $(BUILD)/dem_step_float.o
	$(CC) $(CFLAGS) -Ibench -o $@ bench/dem_step.c $(BUILD)/dem_step_double.o $(BUILD)/dem_step_float.o $(LDLIBS)

# the FEMxDEM driver with float reals, for bench_tradeoff's precision sweep
$(BUILD)/femdem_biaxial_float: examples/femdem_biaxial.c $(HEADERS) $(wildcard examples/*.h) | $(BUILD)
	$(CC) $(CFLAGS) -DGK_REAL_FLOAT -o $@ $< $(LDLIBS)

# bench_tradeoff runs these drivers as child processes
$(BUILD)/bench_tradeoff: | $(BUILD)/femdem_biaxial $(BUILD)/femdem_biaxial_float $(BUILD)/mpmdem_biaxial

$(BUILD)/%: tools/%.c $(HEADERS) | $(BUILD)
	$(CC) $(CFLAGS) -o $@ $< $(LDLIBS)

# ---------------------------------------------------------------- MPI
$(BUILD)/mpi/mpi_%: tests/mpi_%.c $(HEADERS) tests/gk_test.h | $(BUILD)/mpi
	$(MPICC) $(CFLAGS) -o $@ $< $(LDLIBS)

# a runner script per MPI test, so that tests/run_tests.sh runs it as any other test program
$(BUILD)/mpi/run_%: $(BUILD)/mpi/mpi_% | $(BUILD)/mpi
	@printf '#!/bin/sh\nexec %s %s -np 2 %s "$$@"\n' '$(MPIRUN)' '$(MPIRUN_FLAGS)' '$<' > $@ && chmod +x $@

ifeq ($(HAVE_MPI),yes)
mpi: $(MPI_PROGS)
MPI_RUN := $(MPI_RUNNERS)
else
mpi:
	@echo "make mpi: $(MPICC) or $(MPIRUN) not found, the MPI programs are skipped (Debian: apt-get install openmpi-bin libopenmpi-dev)"
MPI_RUN :=
endif

test: $(TESTS) $(EXAMPLES) $(TOOLS) $(if $(HAVE_MPI),$(MPI_PROGS))
	@$(if $(HAVE_MPI),,echo "make test: $(MPICC) not found, the MPI tests are skipped (apt-get install openmpi-bin libopenmpi-dev)";) \
	  tests/run_tests.sh $(TESTS) $(MPI_RUN)

# ---------------------------------------------------------------- check
SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
ASAN_TESTS   := $(patsubst tests/%.c,$(BUILD)/asan/%,$(TEST_SRC))
NOSIMD_TESTS := $(patsubst tests/%.c,$(BUILD)/nosimd/%,$(TEST_SRC))

$(BUILD)/asan/test_%: tests/test_%.c $(HEADERS) tests/gk_test.h | $(BUILD)/asan
	$(CC) $(WARN) -O1 -g $(ARCH) $(FPFLAGS) $(SAN) -Iinclude -Itests -DGK_TEST_QUICK -o $@ $< $(LDLIBS)

$(BUILD)/nosimd/test_%: tests/test_%.c $(HEADERS) tests/gk_test.h | $(BUILD)/nosimd
	$(CC) $(WARN) $(OPT) $(FPFLAGS) -DGK_NO_SIMD -Iinclude -Itests -o $@ $< $(LDLIBS)

check-asan: $(ASAN_TESTS) $(EXAMPLES) $(TOOLS)
	@echo "== tests under AddressSanitizer + UndefinedBehaviorSanitizer"
	@ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 tests/run_tests.sh $(ASAN_TESTS)

check-nosimd: $(NOSIMD_TESTS) $(EXAMPLES) $(TOOLS)
	@echo "== tests built without SIMD (GK_NO_SIMD, no -march)"
	@tests/run_tests.sh $(NOSIMD_TESTS)

# every header alone, declarations and implementation, as C99 with gcc and
# clang, as C++ with g++ and clang++, double and float
check-headers: | $(BUILD)/hdr
	@echo "== header portability"
	@set -e; for h in $(notdir $(HEADERS)); do \
	  for cc in gcc clang; do \
	    for def in "" "-DGK_IMPLEMENTATION" "-DGK_IMPLEMENTATION -DGK_REAL_FLOAT" "-DGK_IMPLEMENTATION -DGK_NO_SIMD"; do \
	      printf '#include "%s"\nint gk__dummy;\n' $$h | $$cc -std=c99 -pedantic -Wall -Wextra -Werror -Wshadow $(ARCH) $$def -Iinclude -x c -c - -o $(BUILD)/hdr/x.o \
	        || { echo "FAILED: $$cc $$def $$h"; exit 1; }; \
	    done; \
	  done; \
	  for cxx in g++ clang++; do \
	    for def in "" "-DGK_IMPLEMENTATION"; do \
	      printf '#include "%s"\nint gk__dummy;\n' $$h | $$cxx -std=c++11 -Wall -Wextra -Werror $(ARCH) $$def -Iinclude -x c++ -c - -o $(BUILD)/hdr/x.o \
	        || { echo "FAILED: $$cxx $$def $$h"; exit 1; }; \
	    done; \
	  done; \
	  echo "ok   $$h (gcc, clang: c99 -pedantic; g++, clang++: c++11; float; no-SIMD)"; \
	done

check: check-headers check-nosimd check-asan

# ---------------------------------------------------------------- run / bench
# the seed 000 FEMxDEM biaxial test at a size that runs in about a minute on
# 2 cores (4 x 8 Q8, 128 RVEs, through the peak); the paper's mesh is
# --nx 8 --ny 16 --steps 100
run: $(BUILD)/femdem_biaxial
	$(BUILD)/femdem_biaxial --nx 4 --ny 8 --element q8 --steps 30 --threads 2 --out $(BUILD)/biaxial

# seed 003's MPMxDEM systems at default sizes of about a minute each on 2
# cores (128-400 RVEs); every driver's --help gives the paper's sizes
run-mpm: $(BUILD)/mpmdem_biaxial
	$(BUILD)/mpmdem_biaxial --threads 2 --out $(BUILD)/mpm_biaxial
run-footing: $(BUILD)/mpmdem_footing
	$(BUILD)/mpmdem_footing --threads 2 --out $(BUILD)/mpm_footing
run-collapse: $(BUILD)/mpmdem_collapse
	$(BUILD)/mpmdem_collapse --threads 2 --out $(BUILD)/mpm_collapse

run-rve: $(BUILD)/rve_path
	$(BUILD)/rve_path --packing examples/data/rve400.txt --dH "0 0.001 0 0" --increments 50 \
	  --steps-per-increment 100 --out $(BUILD)/rve_path.csv

bench: $(BENCHES)
	@for b in $(BENCHES); do echo "== $$b"; $$b || exit 1; done

# issue 6: error against cost over RVE size, DEM steps, float, tangent, mesh,
# element and MPM points per cell (make bench runs the short version)
tradeoff: $(BUILD)/bench_tradeoff
	$(BUILD)/bench_tradeoff --full

bench-peers: $(BUILD)/bench_dem_step
	@bench/peers/run_peers.sh

# ---------------------------------------------------------------- install
install:
	@mkdir -p $(DESTDIR)$(PREFIX)/include/grainkit $(DESTDIR)$(PREFIX)/lib/pkgconfig
	cp $(HEADERS) $(DESTDIR)$(PREFIX)/include/grainkit/
	@printf 'prefix=%s\nincludedir=$${prefix}/include/grainkit\n\nName: grainkit\nDescription: header-only C99 kernels for two-scale granular mechanics (FEMxDEM, MPMxDEM)\nVersion: %s\nCflags: -I$${includedir} -ffp-contract=off\nLibs: -lm\n' \
	  "$(PREFIX)" "$$(sed -n 's/^#define GK_VERSION_STRING "\(.*\)"/\1/p' include/gk_base.h)" \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/grainkit.pc
	@echo "installed headers in $(DESTDIR)$(PREFIX)/include/grainkit, pkg-config file grainkit.pc"

uninstall:
	rm -rf $(DESTDIR)$(PREFIX)/include/grainkit $(DESTDIR)$(PREFIX)/lib/pkgconfig/grainkit.pc

FORMAT_SRC := $(HEADERS) $(TEST_SRC) tests/gk_test.h $(EX_SRC) $(wildcard examples/*.h) $(wildcard bench/*.c bench/*.h) $(TOOL_SRC)
format:
	clang-format -i $(FORMAT_SRC)
format-check:
	clang-format --dry-run --Werror $(FORMAT_SRC)

clean:
	rm -rf $(BUILD)
