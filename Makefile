# grainkit - the only build. `make help` lists the targets.
#
# Every program under examples/, bench/ and tools/ is one C file that defines
# GK_IMPLEMENTATION itself, so each builds with a single compiler call (README's
# quickstart is built that way). This build compiles the implementation once per
# flavour instead (tests/gk_impl.c: normal, MPI, ASan+UBSan, no-SIMD) and links it
# into the tests, drivers and tools (GK_IMPLEMENTATION_ELSEWHERE), as a project of
# several files does; the benchmarks and the float driver keep their own copy.
# Variables you may override: CC, CXX, OPT, ARCH, OMP, PREFIX, BUILD.

CC      ?= cc
CXX     ?= c++
OPT     ?= -O2
ARCH    ?= -march=native
OMP     ?= -fopenmp
BUILD   ?= build
PREFIX  ?= /usr/local

WARN    := -std=c99 -pedantic -Wall -Wextra -Werror
# determinism: no FMA contraction, never -ffast-math (results must not depend on
# the compiler's choice of fused operations)
FPFLAGS := -ffp-contract=off -fno-fast-math
CFLAGS  := $(WARN) $(OPT) $(ARCH) $(FPFLAGS) $(OMP) -Iinclude -Itests
LDLIBS  := -lm

HEADERS  := $(wildcard include/gk_*.h)
TEST_SRC := $(wildcard tests/test_*.c)
EX_SRC   := $(wildcard examples/*.c)
# bench/knockout.c is built by bench/knockout.sh alone, against patched copies of the headers
BENCH_SRC:= $(filter-out bench/%_part.c bench/knockout.c,$(wildcard bench/*.c))
TOOL_SRC := $(wildcard tools/*.c)

TESTS    := $(patsubst tests/%.c,$(BUILD)/%,$(TEST_SRC))

# the optional MPI build (gk_twoscale.h with GK_TWOSCALE_MPI): `make mpi`; `make test` runs its tests
# with 2 ranks when mpicc builds an MPI program (Open MPI: openmpi-bin libopenmpi-dev) and says so when
# not. The probe compiles and links one: mpicc alone is not enough (openmpi-bin, which other packages
# pull in, has mpicc without mpi.h). \043 is the '#' of #include (a bare one starts a comment in make)
MPICC   ?= mpicc
MPIRUN  ?= mpirun
HAVE_MPI := $(shell command -v $(MPIRUN) >/dev/null 2>&1 && \
              printf '\043include <mpi.h>\nint main(int c, char **v) { MPI_Init(&c, &v); return MPI_Finalize(); }\n' | \
              $(MPICC) -x c -o /dev/null - >/dev/null 2>&1 && echo yes)
# Open MPI refuses root without --allow-run-as-root, and more ranks than it counts cores without
# --oversubscribe (other MPIs do not know these flags)
MPIRUN_FLAGS ?= $(shell $(MPIRUN) --version 2>/dev/null | grep -q 'Open MPI' && \
                  { [ "$$(id -u)" = 0 ] && echo '--allow-run-as-root --oversubscribe' || echo '--oversubscribe'; })
# tests/mpi_*.c are MPI programs (mpicc) run on 2 ranks; tests/mpirun_*.c plain programs that launch
# MPI programs themselves (GK_MPIRUN); each gets a runner script for tests/run_tests.sh
MPI_TEST_SRC := $(wildcard tests/mpi_*.c)
MPIRUN_SRC   := $(wildcard tests/mpirun_*.c)
MPI_RUNNERS  := $(patsubst tests/mpi_%.c,$(BUILD)/mpi/run_%,$(MPI_TEST_SRC)) \
                $(patsubst tests/mpirun_%.c,$(BUILD)/mpi/drive_%,$(MPIRUN_SRC))
MPI_PROGS    := $(BUILD)/femdem_biaxial_mpi $(BUILD)/mpi/bench_twoscale_mpi $(MPI_RUNNERS)
EXAMPLES := $(patsubst examples/%.c,$(BUILD)/%,$(EX_SRC))
BENCHES  := $(patsubst bench/%.c,$(BUILD)/bench_%,$(BENCH_SRC))
TOOLS    := $(patsubst tools/%.c,$(BUILD)/%,$(TOOL_SRC))
# fuzz harnesses tests/fuzz/fuzz_NAME.c (seeds in tests/fuzz/corpus/NAME/, findings
# kept in tests/fuzz/crashers/NAME/): found by name, nothing to add here
FUZZ_SRC   := $(wildcard tests/fuzz/fuzz_*.c)
FUZZ_NAMES := $(patsubst tests/fuzz/fuzz_%.c,%,$(FUZZ_SRC))
FUZZ_REPLAY := $(patsubst %,$(BUILD)/fuzz_replay_%,$(FUZZ_NAMES))
# the harnesses of a driver's or a tool's reader compile that program's source in
FUZZ_DEPS   := $(wildcard examples/*.c examples/*.h tools/*.c)

.PHONY: all mpi test check bench bench-peers run run-rve run-mpm run-footing run-collapse run-pipe install uninstall format format-check clean help \
        check-headers check-asan check-nosimd check-smoke check-build tradeoff fuzz

all: $(TESTS) $(EXAMPLES) $(BENCHES) $(TOOLS)

help:
	@echo "make            build tests, examples, benchmarks and tools into $(BUILD)/"
	@echo "make run        the main job: FEMxDEM biaxial test (see README.md)"
	@echo "make run-rve    one RVE along a shear path"
	@echo "make run-mpm | run-footing | run-collapse   MPMxDEM biaxial, footing, column collapse (Liang & Zhao 2019)"
	@echo "make run-pipe   MPMxDEM pipe-soil interaction (Liang & Zhao 2019; about 7 minutes on 2 idle cores)"
	@echo "make test       build and run every test; ends with 'N passed, N failed'"
	@echo "make mpi        the MPI drivers $(BUILD)/*_mpi and $(BUILD)/mpi/ (mpicc; gk_twoscale.h with GK_TWOSCALE_MPI)"
	@echo "make check      tests under ASan+UBSan, a no-SIMD build, header portability, tool smoke runs"
	@echo "make check-build  every program make check runs, built (make -j2 check-build: in parallel)"
	@echo "make fuzz       each libFuzzer harness of tests/fuzz for FUZZ_SECONDS (60) s, one at a time (clang)"
	@echo "make bench      performance programs (2 cores)"
	@echo "make tradeoff   accuracy against cost of the drivers, the whole sweep (10-15 min; build/tradeoff/)"
	@echo "make bench-peers  the same workloads in LAMMPS / LIGGGHTS / YADE when installed"
	@echo "make install PREFIX=dir   headers + pkg-config file"
	@echo "make format / format-check   clang-format"

$(BUILD) $(BUILD)/asan $(BUILD)/nosimd $(BUILD)/hdr $(BUILD)/tests $(BUILD)/fuzz $(BUILD)/mpi:
	@mkdir -p $@

# the tests launch the programs of $(BUILD) and write under $(BUILD)/tests
TESTDEF := -DBUILD='"$(BUILD)"'
# The implementation is compiled once per build (tests/gk_impl.c: normal, ASan+UBSan,
# no-SIMD) and linked into every test, as a project of several files does. A test that
# defines GK_IMPLEMENTATION itself configures it: those of IMPL_VARIANT link an object
# compiled once with that configuration (par64: GK_DEM_PAR_MIN 64, threads on small
# systems, GK_DEM_GATHER_RUNS 4, the rebuild's history copy element by element past 4
# runs, and GK_DEM_GATHER_MAX 0, one thread always scattering, so that its tests compare
# the scatter with the threads' gather, GK_DEM_FREC_MAX 600, 3D scatters through the force
# records up to 600 particles only; also given to the test so that a different value
# in it fails to compile;
# float: GK_REAL_FLOAT); the others (test_untrusted reaches into internals) compile their own.
OWN_IMPL := $(patsubst tests/test_%.c,%,$(shell grep -l '^\#define GK_IMPLEMENTATION' $(TEST_SRC)))
IMPL_VARIANT_dem            := par64
IMPL_VARIANT_scene          := par64
IMPL_VARIANT_extremes_float := float
IMPL_VARIANT_simd_float     := float
IMPLDEF_par64 := -DGK_DEM_PAR_MIN=64 -DGK_DEM_GATHER_RUNS=4 -DGK_DEM_GATHER_MAX=0 -DGK_DEM_FREC_MAX=600
IMPLDEF_float := -DGK_REAL_FLOAT
TESTDEF_par64 := $(IMPLDEF_par64)
# what a test links, $(call impl_for,STEM,THE BUILD'S IMPLEMENTATION OBJECT)
impl_for = $(if $(IMPL_VARIANT_$(1)),$(ELSEWHERE) $(TESTDEF_$(IMPL_VARIANT_$(1))) \
             $(dir $(2))gk_impl_$(IMPL_VARIANT_$(1)).o,$(if $(filter $(1),$(OWN_IMPL)),,$(2)))
IMPL := $(BUILD)/gk_impl.o
$(IMPL): tests/gk_impl.c $(HEADERS) | $(BUILD)
	$(CC) $(CFLAGS) -c -o $@ $<
$(BUILD)/gk_impl_%.o: tests/gk_impl.c $(HEADERS) | $(BUILD)
	$(CC) $(CFLAGS) $(IMPLDEF_$*) -c -o $@ $<
$(foreach t,$(patsubst IMPL_VARIANT_%,%,$(filter IMPL_VARIANT_%,$(.VARIABLES))),$(foreach d,$(BUILD) $(BUILD)/asan $(BUILD)/nosimd,\
  $(eval $(d)/test_$(t): $(d)/gk_impl_$(IMPL_VARIANT_$(t)).o)))
$(BUILD)/test_%: tests/test_%.c $(HEADERS) tests/gk_test.h $(IMPL) | $(BUILD)
	$(CC) $(CFLAGS) $(TESTDEF) -o $@ $< $(call impl_for,$*,$(IMPL)) $(LDLIBS)

# test_mpmdem_footing also tests the footing driver's examples/footing_mech.h directly
$(BUILD)/test_mpmdem_footing $(BUILD)/asan/test_mpmdem_footing $(BUILD)/nosimd/test_mpmdem_footing: examples/footing_mech.h
# test_hybrid_setup tests parts of the hybrid driver (examples/hybrid_*.h) directly
$(BUILD)/test_hybrid_setup $(BUILD)/asan/test_hybrid_setup $(BUILD)/nosimd/test_hybrid_setup: $(wildcard examples/hybrid*.h) examples/cli.h

# the drivers and tools link the implementation object (ELSEWHERE below); the
# quickstart (README's snippet) is built in one compiler call, as a user builds it
$(BUILD)/%: examples/%.c $(HEADERS) $(wildcard examples/*.h) $(IMPL) | $(BUILD)
	$(CC) $(CFLAGS) $(ELSEWHERE) -o $@ $< $(IMPL) $(LDLIBS)
$(BUILD)/quickstart: examples/quickstart.c $(HEADERS) | $(BUILD)
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

$(BUILD)/%: tools/%.c $(HEADERS) $(IMPL) | $(BUILD)
	$(CC) $(CFLAGS) $(ELSEWHERE) -o $@ $< $(IMPL) $(LDLIBS)

# ---------------------------------------------------------------- MPI
# the implementation with the MPI backend of gk_twoscale.h, once, for every MPI program but the benchmark
MPI_IMPL := $(BUILD)/mpi/gk_impl.o
$(MPI_IMPL): tests/gk_impl.c $(HEADERS) | $(BUILD)/mpi
	$(MPICC) $(CFLAGS) -DGK_TWOSCALE_MPI -c -o $@ $<
$(BUILD)/mpi/mpi_%: tests/mpi_%.c $(HEADERS) tests/gk_test.h $(MPI_IMPL) | $(BUILD)/mpi
	$(MPICC) $(CFLAGS) $(ELSEWHERE) $(TESTDEF) -o $@ $< $(MPI_IMPL) $(LDLIBS)

.PRECIOUS: $(BUILD)/mpi/mpi_% $(BUILD)/mpi/mpirun_%
$(BUILD)/mpi/mpirun_%: tests/mpirun_%.c tests/gk_test.h | $(BUILD)/mpi
	$(CC) $(CFLAGS) $(TESTDEF) -o $@ $< $(LDLIBS)

# a runner script per MPI test, so that tests/run_tests.sh runs it as any other test program
$(BUILD)/mpi/run_%: $(BUILD)/mpi/mpi_% | $(BUILD)/mpi
	@printf '#!/bin/sh\nexec %s %s -np 2 %s "$$@"\n' '$(MPIRUN)' '$(MPIRUN_FLAGS)' '$<' > $@ && chmod +x $@
$(BUILD)/mpi/drive_%: $(BUILD)/mpi/mpirun_% | $(BUILD)/mpi
	@printf '#!/bin/sh\nGK_MPIRUN="%s %s" exec %s "$$@"\n' '$(MPIRUN)' '$(MPIRUN_FLAGS)' '$<' > $@ && chmod +x $@

# bench/twoscale.c on MPI ranks (bench/README.md)
$(BUILD)/mpi/bench_twoscale_mpi: bench/twoscale.c $(HEADERS) examples/cli.h | $(BUILD)/mpi
	$(MPICC) $(CFLAGS) -DGK_TWOSCALE_MPI -o $@ $< $(LDLIBS)

# the FEMxDEM driver with its RVEs over MPI ranks (the same results: tests/mpirun_femdem.c)
$(BUILD)/femdem_biaxial_mpi: examples/femdem_biaxial.c $(HEADERS) $(wildcard examples/*.h) $(MPI_IMPL) | $(BUILD)
	$(MPICC) $(CFLAGS) -DGK_TWOSCALE_MPI $(ELSEWHERE) -o $@ $< $(MPI_IMPL) $(LDLIBS)

# the MPMxDEM drivers with their RVEs over MPI ranks (the same results: tests/mpirun_mpmdem.c)
MPI_EXAMPLES := $(patsubst %,$(BUILD)/mpmdem_%_mpi,biaxial footing collapse pipe)
MPI_PROGS    += $(MPI_EXAMPLES)
$(MPI_EXAMPLES): $(BUILD)/%_mpi: examples/%.c $(HEADERS) $(wildcard examples/*.h) $(MPI_IMPL) | $(BUILD)
	$(MPICC) $(CFLAGS) -DGK_TWOSCALE_MPI $(ELSEWHERE) -o $@ $< $(MPI_IMPL) $(LDLIBS)

ifeq ($(HAVE_MPI),yes)
mpi: $(MPI_PROGS)
MPI_RUN := $(MPI_RUNNERS)
else
mpi:
	@echo "make mpi: $(MPICC) cannot build an MPI program or $(MPIRUN) is missing, the MPI programs are skipped (Debian: apt-get install openmpi-bin libopenmpi-dev)"
MPI_RUN :=
endif

# bench_tradeoff too: test_untrusted checks that a failed run fails it
test: $(TESTS) $(EXAMPLES) $(TOOLS) $(FUZZ_REPLAY) $(BUILD)/bench_tradeoff $(if $(HAVE_MPI),$(MPI_PROGS)) | $(BUILD)/tests
	@$(if $(HAVE_MPI),,echo "make test: $(MPICC) cannot build an MPI program or $(MPIRUN) is missing, the MPI tests are skipped (apt-get install openmpi-bin libopenmpi-dev)";) \
	  tests/run_tests.sh $(TESTS) $(FUZZ_REPLAY) $(MPI_RUN)

# the fuzz corpora and every crasher replayed by a plain program (tests/fuzz/replay.c);
# the harness's own GK_IMPLEMENTATION (libFuzzer builds it alone) gives way to the
# build's implementation object (GK_IMPLEMENTATION_ELSEWHERE, gk_base.h)
ELSEWHERE := -DGK_IMPLEMENTATION_ELSEWHERE
$(BUILD)/fuzz_replay_%: tests/fuzz/fuzz_%.c tests/fuzz/replay.c $(wildcard tests/fuzz/*.h) $(HEADERS) $(FUZZ_DEPS) $(IMPL) | $(BUILD)
	$(CC) $(CFLAGS) $(ELSEWHERE) -Itests/fuzz -o $@ tests/fuzz/replay.c $< $(IMPL) $(LDLIBS)

# ---------------------------------------------------------------- check
SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
# -g1 (line tables): sanitizer reports still name file:line and inlined frames,
# at half the compile time of -g; rebuild one program with -g to debug it
SANFLAGS := $(WARN) -O1 -g1 $(ARCH) $(FPFLAGS) $(SAN)
# tests that only run the example programs are left out of the ASan and no-SIMD
# builds: they would run the same -O2 programs again (tests/smoke_asan.sh runs the
# drivers built with ASan+UBSan)
DRIVER_TESTS := examples femdem_dr hybrid_driver mpmdem_biaxial mpmdem_collapse mpmdem_footing mpmdem_pipe
LIB_TESTS    := $(filter-out $(DRIVER_TESTS),$(patsubst tests/test_%.c,%,$(TEST_SRC)))
ASAN_TESTS   := $(patsubst %,$(BUILD)/asan/test_%,$(LIB_TESTS)) $(patsubst %,$(BUILD)/asan/fuzz_replay_%,$(FUZZ_NAMES))
NOSIMD_TESTS := $(patsubst %,$(BUILD)/nosimd/test_%,$(LIB_TESTS))

ASAN_IMPL := $(BUILD)/asan/gk_impl.o
$(ASAN_IMPL): tests/gk_impl.c $(HEADERS) | $(BUILD)/asan
	$(CC) $(SANFLAGS) -Iinclude -c -o $@ $<
$(BUILD)/asan/gk_impl_%.o: tests/gk_impl.c $(HEADERS) | $(BUILD)/asan
	$(CC) $(SANFLAGS) -Iinclude $(IMPLDEF_$*) -c -o $@ $<
$(BUILD)/asan/test_%: tests/test_%.c $(HEADERS) tests/gk_test.h $(ASAN_IMPL) | $(BUILD)/asan
	$(CC) $(SANFLAGS) -Iinclude -Itests -DGK_TEST_QUICK $(TESTDEF) -o $@ $< $(call impl_for,$*,$(ASAN_IMPL)) $(LDLIBS)

$(BUILD)/asan/fuzz_replay_%: tests/fuzz/fuzz_%.c tests/fuzz/replay.c $(wildcard tests/fuzz/*.h) $(HEADERS) $(FUZZ_DEPS) $(ASAN_IMPL) | $(BUILD)/asan
	$(CC) $(SANFLAGS) $(ELSEWHERE) -Iinclude -Itests/fuzz -o $@ tests/fuzz/replay.c $< $(ASAN_IMPL) $(LDLIBS)

# tools and drivers under ASan + UBSan for tests/smoke_asan.sh (a driver joins
# by its name in SMOKE and its runs in the script), linked with the ASan
# implementation object
SMOKE := rve_path gk_pack csv_plot mpmdem_biaxial mpmdem_single mpmdem_footing mpmdem_collapse mpmdem_pipe bench_scene_box femdem_nonlocal femdem_dr hybrid
$(BUILD)/asan/%: examples/%.c $(HEADERS) $(wildcard examples/*.h) $(ASAN_IMPL) | $(BUILD)/asan
	$(CC) $(SANFLAGS) $(ELSEWHERE) -Iinclude -o $@ $< $(ASAN_IMPL) $(LDLIBS)
$(BUILD)/asan/%: tools/%.c $(HEADERS) $(ASAN_IMPL) | $(BUILD)/asan
	$(CC) $(SANFLAGS) $(ELSEWHERE) -Iinclude -o $@ $< $(ASAN_IMPL) $(LDLIBS)
$(BUILD)/asan/bench_%: bench/%.c $(HEADERS) $(ASAN_IMPL) | $(BUILD)/asan
	$(CC) $(SANFLAGS) $(ELSEWHERE) -Iinclude -o $@ $< $(ASAN_IMPL) $(LDLIBS)

check-smoke: $(patsubst %,$(BUILD)/asan/%,$(SMOKE)) | $(BUILD)/tests
	@echo "== tool and driver smoke runs under AddressSanitizer + UndefinedBehaviorSanitizer, leaks included"
	@B=$(BUILD)/asan T=$(BUILD)/tests/smoke tests/run_tests.sh tests/smoke_asan.sh

NOSIMDFLAGS := $(WARN) $(OPT) $(FPFLAGS) -DGK_NO_SIMD -Iinclude
NOSIMD_IMPL := $(BUILD)/nosimd/gk_impl.o
$(NOSIMD_IMPL): tests/gk_impl.c $(HEADERS) | $(BUILD)/nosimd
	$(CC) $(NOSIMDFLAGS) -c -o $@ $<
$(BUILD)/nosimd/gk_impl_%.o: tests/gk_impl.c $(HEADERS) | $(BUILD)/nosimd
	$(CC) $(NOSIMDFLAGS) $(IMPLDEF_$*) -c -o $@ $<
$(BUILD)/nosimd/test_%: tests/test_%.c $(HEADERS) tests/gk_test.h $(NOSIMD_IMPL) | $(BUILD)/nosimd
	$(CC) $(NOSIMDFLAGS) -Itests $(TESTDEF) -o $@ $< $(call impl_for,$*,$(NOSIMD_IMPL)) $(LDLIBS)

check-asan: $(ASAN_TESTS) $(EXAMPLES) $(TOOLS) | $(BUILD)/tests
	@echo "== tests under AddressSanitizer + UndefinedBehaviorSanitizer"
	@ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 tests/run_tests.sh $(ASAN_TESTS)

check-nosimd: $(NOSIMD_TESTS) $(EXAMPLES) $(TOOLS) | $(BUILD)/tests
	@echo "== tests built without SIMD (GK_NO_SIMD, no -march)"
	@tests/run_tests.sh $(NOSIMD_TESTS)

# every header alone, declarations and implementation, as C99 with gcc and
# clang, as C++ with g++ and clang++, double and float; and the headers of
# STANDALONE with only their own GK_X_IMPLEMENTATION: every grainkit function
# they call is then defined (the FEM family implements what it includes)
STANDALONE := gk_sparse.h gk_mesh.h gk_dofmap.h gk_nonlocal.h gk_fem.h
# one stamp per header (make -j runs them in parallel; check-build makes them too)
HDR_OK   := $(patsubst include/%.h,$(BUILD)/hdr/%.ok,$(HEADERS)) \
            $(patsubst %.h,$(BUILD)/hdr/%.alone,$(STANDALONE))
$(BUILD)/hdr/%.ok: include/%.h $(HEADERS) | $(BUILD)/hdr
	@set -e; h=$*.h; \
	for cc in gcc clang; do \
	  for def in "" "-DGK_IMPLEMENTATION" "-DGK_IMPLEMENTATION -DGK_REAL_FLOAT" "-DGK_IMPLEMENTATION -DGK_NO_SIMD"; do \
	    printf '#include "%s"\nint gk__dummy;\n' $$h | $$cc -std=c99 -pedantic -Wall -Wextra -Werror -Wshadow $(ARCH) $$def -Iinclude -x c -fsyntax-only - \
	      || { echo "FAILED: $$cc $$def $$h"; exit 1; }; \
	  done; \
	done; \
	for cxx in g++ clang++; do \
	  for def in "" "-DGK_IMPLEMENTATION"; do \
	    printf '#include "%s"\nint gk__dummy;\n' $$h | $$cxx -std=c++11 -Wall -Wextra -Werror $(ARCH) $$def -Iinclude -x c++ -fsyntax-only - \
	      || { echo "FAILED: $$cxx $$def $$h"; exit 1; }; \
	  done; \
	done; \
	echo "ok   $$h (gcc, clang: c99 -pedantic; g++, clang++: c++11; float; no-SIMD)"; touch $@
$(BUILD)/hdr/%.alone: include/%.h $(HEADERS) | $(BUILD)/hdr
	@set -e; h=$*.h; o=$(BUILD)/hdr/$*.o; \
	m=GK_$$(echo $$h | sed 's/^gk_//; s/\.h$$//' | tr a-z A-Z)_IMPLEMENTATION; \
	for cc in "gcc -std=c99 -pedantic -x c" "g++ -std=c++11 -x c++"; do \
	  printf '#include "%s"\nint gk__dummy;\n' $$h | $$cc -Wall -Wextra -Werror -Wshadow $(ARCH) \
	    -DGK_BASE_IMPLEMENTATION -D$$m -Iinclude -c - -o $$o \
	    || { echo "FAILED: $$cc -D$$m $$h"; exit 1; }; \
	  u=$$(nm -u $$o | awk '$$2 ~ /^_?gk_/ {print $$2}' | tr '\n' ' '); \
	  [ -z "$$u" ] || { echo "FAILED: $$h with $$m alone leaves undefined: $$u"; exit 1; }; \
	  for f in $$(sed -n 's/^GKDEF[^(]*[ *]\(gk_[a-z0-9_]*\)(.*/\1/p' include/$$h); do \
	    nm --defined-only $$o | grep -q " T _\{0,1\}$$f$$" \
	      || { echo "FAILED: $$h with $$m alone does not define $$f"; exit 1; }; \
	  done; \
	done; \
	echo "ok   $$h alone with GK_BASE_IMPLEMENTATION + $$m: defines all it declares, calls nothing undefined"; touch $@
# every program also compiles with clang (the build uses $(CC)): one stamp per program
PROG_SRC := $(filter-out tests/test_%.c,$(EX_SRC) $(BENCH_SRC) $(TOOL_SRC)) $(TEST_SRC) $(MPIRUN_SRC)
HDR_OK   += $(patsubst %.c,$(BUILD)/hdr/%.clang,$(PROG_SRC))
$(BUILD)/hdr/%.clang: %.c $(HEADERS) $(wildcard examples/*.h bench/*.h bench/*_part.c) tests/gk_test.h | $(BUILD)/hdr
	@mkdir -p $(@D) && clang $(WARN) $(ARCH) $(FPFLAGS) -fopenmp -Iinclude -Itests -Ibench $(TESTDEF) -fsyntax-only $< \
	  && touch $@ || { echo "FAILED: clang $<"; exit 1; }
check-headers: $(HDR_OK)
	@echo "== header portability: every header alone, $(words $(HEADERS)) headers, and $(words $(STANDALONE)) of them with only their own implementation; every program with clang: ok"

# the four checks one after the other, even under -jN (the no-SIMD and the ASan tests
# write the same files); inside each, -jN builds N at a time and runs N test programs
# at a time (tests/run_tests.sh)
check:
	@$(MAKE) --no-print-directory check-headers
	@$(MAKE) --no-print-directory check-nosimd
	@$(MAKE) --no-print-directory check-asan
	@$(MAKE) --no-print-directory check-smoke

# every program make check runs, built and not run: `make -j2 check-build && make -j2 check`
# compiles two at a time, then runs the checks
check-build: $(HDR_OK) $(ASAN_TESTS) $(NOSIMD_TESTS) $(patsubst %,$(BUILD)/asan/%,$(SMOKE)) $(EXAMPLES) $(TOOLS)

# ---------------------------------------------------------------- run / bench
# the FEMxDEM biaxial test of Guo & Zhao (2014) at a size that runs in about a minute on
# 2 cores (4 x 8 Q8, 128 RVEs, through the peak); examples/README.md has the
# larger runs
run: $(BUILD)/femdem_biaxial
	$(BUILD)/femdem_biaxial --nx 4 --ny 8 --element q8 --steps 30 --threads 2 --out $(BUILD)/biaxial

# the MPMxDEM systems of Liang & Zhao (2019) at default sizes of about a minute each on 2
# cores (128-400 RVEs); every driver's --help gives the paper's sizes
run-mpm: $(BUILD)/mpmdem_biaxial
	$(BUILD)/mpmdem_biaxial --threads 2 --out $(BUILD)/mpm_biaxial
run-footing: $(BUILD)/mpmdem_footing
	$(BUILD)/mpmdem_footing --threads 2 --out $(BUILD)/mpm_footing
run-collapse: $(BUILD)/mpmdem_collapse
	$(BUILD)/mpmdem_collapse --threads 2 --out $(BUILD)/mpm_collapse
run-pipe: $(BUILD)/mpmdem_pipe
	$(BUILD)/mpmdem_pipe --threads 2 --out $(BUILD)/mpm_pipe

run-rve: $(BUILD)/rve_path
	$(BUILD)/rve_path --packing examples/data/rve400.txt --dH "0 0.001 0 0" --increments 50 \
	  --steps-per-increment 100 --out $(BUILD)/rve_path.csv

bench: $(BENCHES)
	@for b in $(BENCHES); do echo "== $$b"; $$b || { echo "make bench: $$b failed (exit $$?)"; exit 1; }; done

# error against cost over RVE size, DEM steps, float, tangent, mesh, element
# and MPM points per cell (make bench runs the short version)
tradeoff: $(BUILD)/bench_tradeoff
	$(BUILD)/bench_tradeoff --full

# libFuzzer (clang, libclang-rt-dev): each harness for FUZZ_SECONDS, one at a time;
# new inputs in build/fuzz/NAME/, findings in build/fuzz/NAME-crash-*
FUZZ_SECONDS ?= 60
FUZZ_CC ?= clang
$(BUILD)/fuzz/fuzz_%: tests/fuzz/fuzz_%.c $(wildcard tests/fuzz/*.h) $(HEADERS) $(FUZZ_DEPS) | $(BUILD)/fuzz
	$(FUZZ_CC) -std=c99 -g -O1 $(FPFLAGS) -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
	  -Iinclude -Itests/fuzz -o $@ $< -lm

fuzz: $(patsubst %,$(BUILD)/fuzz/fuzz_%,$(FUZZ_NAMES))
	@set -e; for n in $(FUZZ_NAMES); do \
	  mkdir -p $(BUILD)/fuzz/$$n; echo "== fuzz_$$n for $(FUZZ_SECONDS) s"; \
	  seeds=tests/fuzz/corpus/$$n; [ -d tests/fuzz/crashers/$$n ] && seeds="$$seeds tests/fuzz/crashers/$$n"; \
	  if $(BUILD)/fuzz/fuzz_$$n -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 \
	       -artifact_prefix=$(BUILD)/fuzz/$$n- $(BUILD)/fuzz/$$n $$seeds > $(BUILD)/fuzz/$$n.log 2>&1; then \
	    grep -E '^(stat::number_of_executed_units|stat::peak_rss_mb|Done)' $(BUILD)/fuzz/$$n.log; \
	  else \
	    tail -n 30 $(BUILD)/fuzz/$$n.log; \
	    echo "make fuzz: fuzz_$$n found a crash: $(BUILD)/fuzz/$$n-crash-* (log $(BUILD)/fuzz/$$n.log);" \
	      "fix it, then keep the input in tests/fuzz/crashers/$$n/"; exit 1; \
	  fi; \
	done

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
