# flexmbs — `make run` and `make test` set up a fresh Debian machine, build and run.
#
#   make run     install what is missing, build (release), run the main example; the
#                executable is then also build/bin/flexmbs (a link to the release build)
#   make test    install what is missing, build (debug, bounds checks), run every suite
#   make bench   install what is missing, build (release), run the benchmarks
#   make paper   the paper's studies on the five-body mechanism (coarse and fine coupler
#                mesh, about 12 min) into results/
#   make extremes  every solver at extreme tolerances, materials and times
#   make check-memory  install valgrind if missing, build (debug), run the numerical
#                suites and every scene of inputs/ (cut to a few steps) under valgrind
#   make install PREFIX=...   install library (static and shared), modules, the classic
#                faces and pkg-config files (docs/packaging.md)
#   make docs    the API documentation (FORD, in a virtual environment) into build/docs/api/
#   make build-mpi  (or make build MPI=1) install OpenMPI and MUMPS's MPI build if missing,
#                build flexmbs on them (release): build/bin/flexmbs-mpi, for mpirun -n N /
#                srun -n N (docs/large_scenes.md)
#   make test-mpi  the same (debug): scenes on 1 and 2 ranks and under srun -n 2 on a
#                one-node Slurm, against the sequential build
#   OPENMP=1     (with any of them) thread the finite-element assembly
#   LTO=1        (with any of them) link-time optimisation

SHELL := /bin/bash
.DEFAULT_GOAL := run

APT_PACKAGES := gfortran libsundials-dev libsundials-fortran-dev libsuitesparse-dev \
                liblapack-dev libopenblas-dev libhdf5-dev libmumps-seq-dev libarpack2-dev \
                python3-h5py pkgconf python3-matplotlib python3-venv
BUILD        := $(CURDIR)/build
VENV         := $(BUILD)/venv
FORD_VERSION := 7.0.13
FORD_VENV    := $(BUILD)/ford-venv
# meshio and VTK from PyPI for test/vtk_files.py, beside the system's h5py
# and numpy (python3-h5py; --system-site-packages)
PY_VENV      := $(BUILD)/py-venv
PY_PACKAGES  := meshio==5.3.5 vtk==9.7.2
# One set of flags for every fpm call: changing them makes fpm rebuild everything.
# MUMPS's Fortran headers (dmumps_struc.h, ...) are in /usr/include, which
# gfortran does not search for INCLUDE lines; the sequential library's
# mpif.h is in /usr/include/mumps_seq.
export FPM_FFLAGS := -I/usr/include/hdf5/serial -I/usr/include/sundials/fortran \
                     -I/usr/include -I/usr/include/mumps_seq
# -fPIC: the C shims go into libflexmbs.so as well (fpm compiles every
# Fortran object with -fPIC already, in both profiles).
export FPM_CFLAGS := -I/usr/include/suitesparse -fPIC
# LTO=1 adds link-time optimisation (inlines the dual-number operators of
# the AD mode across modules; fat objects keep the library linkable without it).
ifeq ($(LTO),1)
export FPM_FFLAGS := $(FPM_FFLAGS) -flto -ffat-lto-objects
export FPM_LDFLAGS := $(FPM_LDFLAGS) -flto
endif
# OPENMP=1 threads the finite-element assembly (results bitwise identical).
ifeq ($(OPENMP),1)
export FPM_FFLAGS := $(FPM_FFLAGS) -fopenmp
export FPM_LDFLAGS := $(FPM_LDFLAGS) -fopenmp
OMP_LINK := -fopenmp
endif
FPM          = $(shell command -v fpm 2>/dev/null || echo $(VENV)/bin/fpm)
PREFIX_DEBUG   := $(BUILD)/prefix-debug
# The umbrella module (src/flexmbs.f90) is compiled only by --no-prune
# installs, and fpm does not rebuild its object when a module it uses
# changes: a stale one gave the examples a mismatched `use flexmbs` (they
# crashed). Removed before every install, it is rebuilt in a second.
UMBRELLA_OBJECTS = $(wildcard $(BUILD)/gfortran_*/flexmbs/src_flexmbs.f90.o*)
PREFIX_RELEASE := $(BUILD)/prefix-release
PREFIX       ?= /usr/local
# The link line a user needs after the flexmbs library (docs/library.md).
SYSLIBS      := -lsundials_fida_mod -lsundials_fnvecserial_mod \
                -lsundials_fsunmatrixdense_mod -lsundials_fsunmatrixsparse_mod \
                -lsundials_fsunlinsoldense_mod -lsundials_fsunlinsolklu_mod \
                -lsundials_ida -lsundials_nvecserial -lsundials_sunmatrixdense \
                -lsundials_sunmatrixsparse -lsundials_sunlinsoldense -lsundials_sunlinsolklu \
                -lsundials_generic \
                -lklu -lcholmod -lamd -lcolamd -lbtf -lsuitesparseconfig \
                -ldmumps_seq -lzmumps_seq -lmumps_common_seq -lmpiseq_seq -lpord_seq \
                -lhdf5_serial_fortran -lhdf5_serial -larpack -llapack -lblas
MAIN_INPUT   := inputs/five_body.nml
VERSION      := $(shell sed -n 's/^version *= *"\(.*\)"/\1/p' fpm.toml)

# pkg-config files of an install under $(1) (pkgconfig/*.pc.in): then
# `gfortran prog.f90 $$(pkg-config --cflags --libs flexmbs)` builds a program
# (static: libflexmbs.a), flexmbs-shared links libflexmbs.so (docs/packaging.md).
define write_pkgconfig
	@mkdir -p $(1)/lib/pkgconfig
	@for pc in flexmbs flexmbs-shared flexmbs-legacy; do \
	    sed -e 's#@PREFIX@#$(1)#' -e 's#@VERSION@#$(VERSION)#' \
	        -e 's#@SYSLIBS@#$(strip $(OMP_LINK) $(SYSLIBS))#' \
	        pkgconfig/$$pc.pc.in > $(1)/lib/pkgconfig/$$pc.pc || exit 1; \
	done
endef

# libflexmbs.so beside libflexmbs.a under $(1)/lib: the archive's objects
# (all -fPIC) linked whole into a shared library that names the system
# libraries it needs, so that a program links it with -lflexmbs alone
# (--no-undefined: none is missing). The soname is the full version: the
# module files, and so the ABI, change from one version to the next.
define install_shared_library
	@gfortran -shared -o $(1)/lib/libflexmbs.so.$(VERSION) \
	    -Wl,-soname,libflexmbs.so.$(VERSION) -Wl,--no-undefined \
	    -Wl,--whole-archive $(1)/lib/libflexmbs.a -Wl,--no-whole-archive \
	    $(FPM_LDFLAGS) $(SYSLIBS)
	@ln -sf libflexmbs.so.$(VERSION) $(1)/lib/libflexmbs.so
endef

.PHONY: run test bench paper extremes check-memory deps build build-debug install legacy-test \
        docs clean help py-venv build-mpi mpi-project test-mpi

# The MPI build: MUMPS's MPI library (libmumps-dev, on OpenMPI) instead of
# the sequential one, in a project of its own under build/mpi (its fpm.toml
# made from ours with the MPI libraries, the sources linked in), so that the
# sequential build, the default, is never touched. OpenMPI's mpif.h comes
# first; -DFLEXMBS_MPI tells the code (linalg/mumps_service).
MPI_PACKAGES := libmumps-dev libopenmpi-dev openmpi-bin
MPI_DIR      := $(BUILD)/mpi
MPI_FFLAGS    = -I$(firstword $(shell mpicc --showme:incdirs 2>/dev/null)) \
                -I/usr/include/hdf5/serial -I/usr/include/sundials/fortran -I/usr/include \
                -DFLEXMBS_MPI $(filter -fopenmp -flto -ffat-lto-objects,$(FPM_FFLAGS))
MPI_LDFLAGS   = $(addprefix -L,$(shell mpicc --showme:libdirs 2>/dev/null) \
                $(shell mpif90 --showme:libdirs 2>/dev/null)) $(FPM_LDFLAGS)
MPI_FPM       = cd $(MPI_DIR) && FPM_FFLAGS="$(MPI_FFLAGS)" FPM_LDFLAGS="$(MPI_LDFLAGS)" $(FPM)

mpi-project:
	@$(MAKE) --no-print-directory deps EXTRA_PACKAGES="$(MPI_PACKAGES)"
	@mkdir -p $(MPI_DIR)
	@sed -e 's/"dmumps_seq", "zmumps_seq", "mumps_common_seq", "mpiseq_seq", "pord_seq"/"dmumps", "zmumps", "mumps_common", "pord", "mpi_mpifh", "mpi"/' \
	    -e '/^\[\[example\]\]/,$$d' fpm.toml > $(MPI_DIR)/fpm.toml.new
	@grep -q '"mpi_mpifh"' $(MPI_DIR)/fpm.toml.new \
	    || { echo "make: fpm.toml's MUMPS libraries not found for the MPI build" >&2; exit 1; }
	@cmp -s $(MPI_DIR)/fpm.toml.new $(MPI_DIR)/fpm.toml && rm $(MPI_DIR)/fpm.toml.new \
	    || mv $(MPI_DIR)/fpm.toml.new $(MPI_DIR)/fpm.toml
	@for d in src app test; do ln -sfn $(CURDIR)/$$d $(MPI_DIR)/$$d; done

# The MPI build against the sequential one (test/mpi.sh): scenes on 1 and
# 2 ranks, the refusals, srun -n 2 on a one-node Slurm (slurm-wlm, munge).
test-mpi: mpi-project
	@$(MAKE) --no-print-directory deps EXTRA_PACKAGES="$(MPI_PACKAGES) slurm-wlm munge"
	@$(FPM) build --profile debug > /dev/null
	@$(MPI_FPM) build --profile debug > /dev/null
	@seq=$$($(FPM) run --profile debug --runner echo flexmbs 2>/dev/null | tail -1); \
	    mpi=$$($(MPI_FPM) run --profile debug --runner echo flexmbs 2>/dev/null | tail -1); \
	    bash test/mpi.sh "$$seq" "$(MPI_DIR)/$$mpi"

build-mpi: mpi-project
	$(MPI_FPM) build --profile release
	@mkdir -p $(BUILD)/bin
	@exe=$$($(MPI_FPM) run --profile release flexmbs --runner echo 2>/dev/null | tail -1); \
	    [ -x "$(MPI_DIR)/$$exe" ] || { echo "make build-mpi: no executable (got '$$exe')" >&2; exit 1; }; \
	    ln -sfn "$$(readlink -f "$(MPI_DIR)/$$exe")" $(BUILD)/bin/flexmbs-mpi

help:
	@echo "make run | make test | make bench | make paper | make check-memory |" \
	    "make install PREFIX=dir | make docs | make clean"

# Install the system packages and fpm when they are missing (make paper
# adds gnuplot for its plots, make check-memory valgrind).
deps:
	@missing=""; \
	for p in $(APT_PACKAGES) $(EXTRA_PACKAGES); do \
	    dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" \
	        || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	    echo "installing:$$missing"; \
	    SUDO=""; [ "$$(id -u)" -ne 0 ] && SUDO=sudo; \
	    $$SUDO apt-get update -qq && \
	    DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null \
	        || { echo "apt-get install failed for:$$missing" >&2; exit 1; }; \
	fi
	@if ! command -v fpm >/dev/null 2>&1 && [ ! -x $(VENV)/bin/fpm ]; then \
	    echo "installing fpm"; \
	    pip install --quiet fpm 2>/dev/null || pip3 install --quiet fpm 2>/dev/null || \
	    { python3 -m venv $(VENV) && $(VENV)/bin/pip install --quiet fpm; } || \
	    { echo "could not install fpm" >&2; exit 1; }; \
	fi

# build/bin/flexmbs links the release executable (whose folder name fpm
# derives from the flags), so that a user can put build/bin on PATH.
# MPI=1: the MPI build instead (make build-mpi: build/bin/flexmbs-mpi).
build: deps
ifeq ($(MPI),1)
	@$(MAKE) --no-print-directory build-mpi
else
	$(FPM) build --profile release
	@mkdir -p $(BUILD)/bin
	@exe=$$($(FPM) run --profile release flexmbs --runner echo 2>/dev/null | tail -1); \
	    [ -x "$$exe" ] || { echo "make build: no release executable (got '$$exe')" >&2; exit 1; }; \
	    ln -sfn "$$(readlink -f "$$exe")" $(BUILD)/bin/flexmbs
endif

build-debug: deps
	$(FPM) build --profile debug

run: build
	$(BUILD)/bin/flexmbs run $(MAIN_INPUT)
	@echo "flexmbs is $(BUILD)/bin/flexmbs; to run it as 'flexmbs':"
	@echo "    export PATH=\"$(BUILD)/bin:\$$PATH\""

# Root suites, then the classic fixed-form drivers linked against the
# installed library exactly as a user links them, the example programs of
# examples/ built the same way and run, one also against the shared library
# (test/programs.sh), a project depending on flexmbs through fpm
# (test/dependency.sh, test/fpm_dependency/), the architecture's rules
# on the sources (test/layers.py), the documentation of every public
# procedure and type (test/public_docs.py), the typed scene generated from
# the schema and current (test/scene_records.py), then the command-line
# checks of test/cli.sh, the documentation's links and generated scene
# reference (test/docs.py), the ParaView and XDMF files read by VTK and
# meshio (test/vtk_files.py, in $(PY_VENV)), the signals of test/kill.sh (python3-h5py reads
# the files they leave), runs killed and resumed from their checkpoints
# (test/restart.sh), every example scene with empty standard error
# (test/examples.sh), DDASSL and IDA from 1e-2 to 1e-12 on the scenes
# against RADAU5 (test/tolerances.sh) and the fuzzer of the scene input (test/fuzz, about
# a thousand mutated scenes, two at a time); one summary line last.
test: deps
	@mkdir -p $(BUILD)
	@set -o pipefail; $(FPM) test --profile debug 2>&1 | tee $(BUILD)/test-root.log; \
	    echo "exit $$?" >> $(BUILD)/test-root.log
	@$(MAKE) --no-print-directory legacy-test PREFIX_USED=$(PREFIX_DEBUG) PROFILE=debug \
	    > $(BUILD)/test-legacy.log 2>&1; echo "exit $$?" >> $(BUILD)/test-legacy.log; \
	    cat $(BUILD)/test-legacy.log
	@set -o pipefail; bash test/programs.sh $(PREFIX_DEBUG) 2>&1 | tee $(BUILD)/test-programs.log; \
	    echo "exit $$?" >> $(BUILD)/test-programs.log
	@set -o pipefail; FPM="$(FPM)" bash test/dependency.sh 2>&1 | tee $(BUILD)/test-dependency.log; \
	    echo "exit $$?" >> $(BUILD)/test-dependency.log
	@set -o pipefail; python3 test/layers.py 2>&1 | tee $(BUILD)/test-layers.log; \
	    echo "exit $$?" >> $(BUILD)/test-layers.log
	@set -o pipefail; python3 test/public_docs.py 2>&1 | tee $(BUILD)/test-public-docs.log; \
	    echo "exit $$?" >> $(BUILD)/test-public-docs.log
	@set -o pipefail; python3 test/scene_records.py 2>&1 | tee $(BUILD)/test-scene-records.log; \
	    echo "exit $$?" >> $(BUILD)/test-scene-records.log
	@set -o pipefail; FPM="$(FPM)" bash test/cli.sh 2>&1 | tee $(BUILD)/test-cli.log; \
	    echo "exit $$?" >> $(BUILD)/test-cli.log
	@set -o pipefail; FLEXMBS_PKGCONFIG=$(PREFIX_DEBUG)/lib/pkgconfig python3 test/docs.py \
	    "$$($(FPM) run --profile debug --runner echo flexmbs 2>/dev/null | tail -n 1)" 2>&1 \
	    | tee $(BUILD)/test-docs.log; echo "exit $$?" >> $(BUILD)/test-docs.log
	@set -o pipefail; { $(MAKE) --no-print-directory py-venv && $(PY_VENV)/bin/python \
	    test/vtk_files.py "$$($(FPM) run --profile debug --runner echo flexmbs 2>/dev/null \
	    | tail -n 1)"; } 2>&1 | tee $(BUILD)/test-vtk.log; echo "exit $$?" >> $(BUILD)/test-vtk.log
	@set -o pipefail; FPM="$(FPM)" bash test/kill.sh 2>&1 | tee $(BUILD)/test-kill.log; \
	    echo "exit $$?" >> $(BUILD)/test-kill.log
	@set -o pipefail; FPM="$(FPM)" bash test/restart.sh 2>&1 | tee $(BUILD)/test-restart.log; \
	    echo "exit $$?" >> $(BUILD)/test-restart.log
	@set -o pipefail; FPM="$(FPM)" bash test/examples.sh 2>&1 | tee $(BUILD)/test-examples.log; \
	    echo "exit $$?" >> $(BUILD)/test-examples.log
	@set -o pipefail; FPM="$(FPM)" bash test/tolerances.sh 2>&1 | tee $(BUILD)/test-tolerances.log; \
	    echo "exit $$?" >> $(BUILD)/test-tolerances.log
	@set -o pipefail; FPM="$(FPM)" bash test/fuzz/run.sh 2>&1 | tee $(BUILD)/test-fuzz.log; \
	    echo "exit $$?" >> $(BUILD)/test-fuzz.log
	@bash test/summarize.sh $(BUILD)/test-root.log $(BUILD)/test-legacy.log \
	    $(BUILD)/test-programs.log $(BUILD)/test-dependency.log $(BUILD)/test-layers.log \
	    $(BUILD)/test-public-docs.log $(BUILD)/test-scene-records.log $(BUILD)/test-cli.log $(BUILD)/test-docs.log \
	    $(BUILD)/test-vtk.log $(BUILD)/test-kill.log $(BUILD)/test-restart.log \
	    $(BUILD)/test-examples.log \
	    $(BUILD)/test-tolerances.log $(BUILD)/test-fuzz.log

PROFILE     ?= debug
PREFIX_USED ?= $(PREFIX_DEBUG)
LEGACY_DRIVERS := $(wildcard legacy/test/*.f)
LEGACY_MODERN  := $(wildcard legacy/test/*.f90)

# Classic drivers: plain `gfortran -std=legacy`, linked against the install
# with the link line of its pkg-config file (flexmbs-legacy.pc); modern
# callers (*.f90) use the installed interface modules. The root is installed
# too (--no-prune: the whole library), for `-lflexmbs`, with its shared
# library as `make install` makes it (test/programs.sh links one).
legacy-test:
	@rm -f $(UMBRELLA_OBJECTS)
	@$(FPM) install --no-prune --profile $(PROFILE) --prefix $(PREFIX_USED) >/dev/null
	@cd legacy && $(FPM) install --profile $(PROFILE) --prefix $(PREFIX_USED) >/dev/null
	$(call write_pkgconfig,$(PREFIX_USED))
	$(call install_shared_library,$(PREFIX_USED))
	@mkdir -p $(BUILD)/legacy-test
	@for src in $(LEGACY_DRIVERS) $(LEGACY_MODERN); do \
	    name=$$(basename $$src); exe=$(BUILD)/legacy-test/$${name%.*}; \
	    case $$src in \
	        *.f) flags="-std=legacy" ;; \
	        *) flags="-std=f2018 -J$(BUILD)/legacy-test $$(PKG_CONFIG_PATH=$(PREFIX_USED)/lib/pkgconfig \
	               pkg-config --cflags flexmbs-legacy)" ;; \
	    esac; \
	    echo "== $$src"; \
	    gfortran $$flags $(OMP_LINK) -o $$exe $$src \
	        $$(PKG_CONFIG_PATH=$(PREFIX_USED)/lib/pkgconfig pkg-config --libs flexmbs-legacy) \
	        || { echo "FAIL compile $$src"; continue; }; \
	    ( cd $(BUILD)/legacy-test && $$exe ) || echo "FAIL run $$src (exit $$?)"; \
	done

# libflexmbs.a needs --no-prune: fpm would otherwise keep only what app/ uses.
install: deps
	@rm -f $(UMBRELLA_OBJECTS)
	$(FPM) install --no-prune --profile release --prefix $(PREFIX)
	cd legacy && $(FPM) install --profile release --prefix $(PREFIX)
	$(call write_pkgconfig,$(abspath $(PREFIX)))
	$(call install_shared_library,$(abspath $(PREFIX)))

# The paper's studies (inputs/paper/five_body_*.nml) into results/, on the
# coarse and on the fine coupler mesh: the references (two at a time), then
# the sweeps in two processes; each sweep's log and table.
PAPER_SWEEPS := five_body_table3 five_body_table2 five_body_figure6 five_body_table2_undamped \
                five_body_table2_viscosity_100 five_body_table2_viscosity_10 \
                five_body_fine_table3 five_body_fine_table2 five_body_fine_figure6 \
                five_body_fine_table2_undamped five_body_fine_table3_window
PAPER_REFERENCES := five_body_table3:reference five_body_table2_undamped:reference_undamped \
                    five_body_table2_viscosity_100:reference_viscosity_100 \
                    five_body_table2_viscosity_10:reference_viscosity_10 \
                    five_body_fine_table3:reference_fine \
                    five_body_fine_table2_undamped:reference_fine_undamped \
                    five_body_fine_table3_window:reference_fine_window
# x of the coupler's middle node (node 23 of its 3 x 5 x 3 grid) in y: after
# 4 bodies x 7 coordinates and the chain's 2, its x is free coordinate 67
MIDDLE_NODE_X := 97
# The fine mesh (6 x 21 x 6 nodes) has no node at the coupler's centre: its
# x there is the mean of the four nodes around it on the face y = 0.2 (the
# hexahedra's interpolation at that face centre), nodes 315, 316, 441, 442.
MIDDLE_FINE_X := 973 976 1351 1354
paper:
	@$(MAKE) --no-print-directory deps EXTRA_PACKAGES=gnuplot-nox
	$(FPM) build --profile release
	@mkdir -p results
	@bin=$$($(FPM) run --profile release flexmbs --runner echo 2>/dev/null | tail -1); \
	export OPENBLAS_NUM_THREADS=1; \
	echo $(PAPER_REFERENCES) | tr ' ' '\n' | xargs -P 2 -I{} sh -c \
	    's={}; '"$$bin"' reference inputs/paper/$${s%%:*}.nml --quiet > results/$${s#*:}.txt 2>&1'; \
	for r in $(PAPER_REFERENCES); do \
	    cat results/$${r#*:}.txt; \
	    grep -q '^written' results/$${r#*:}.txt \
	        || { echo "make paper: the reference of $${r%%:*} failed" >&2; exit 1; }; \
	done; \
	for s in $(PAPER_SWEEPS); do \
	    $$bin sweep inputs/paper/$$s.nml -j 2 --quiet > results/$$s.txt 2>&1 \
	        || { cat results/$$s.txt; exit 1; }; \
	    cat results/$$s.txt; \
	done; \
	$$bin columns results/five_body_reference.h5 $(MIDDLE_NODE_X) > results/figure5_damped.txt && \
	$$bin columns results/five_body_undamped_reference.h5 $(MIDDLE_NODE_X) \
	    > results/figure5_undamped.txt && \
	for v in fine:five_body_fine fine_undamped:five_body_fine_undamped; do \
	    $$bin columns results/$${v#*:}_reference.h5 $(MIDDLE_FINE_X) \
	        | awk '/^#/ { print; next } { printf "%.15e %.15e\n", $$1, ($$2 + $$3 + $$4 + $$5) / 4 }' \
	        > results/figure5_$${v%%:*}.txt || exit 1; \
	done && \
	gnuplot inputs/paper/plots.gp && \
	bash inputs/paper/frames.sh $$bin results/five_body_reference.h5 results/five_body_frames.png && \
	ls results/*.png

# The extremes study (inputs/paper/extremes.sh) into results/extremes/: the
# five-body mechanism, its fine mesh and the 16 335-coordinate coupler;
# VARIANTS picks others (damped fine undamped soft stiff long large),
# VARIANTS=all runs all seven.
VARIANTS ?= damped fine large
extremes: deps
	$(FPM) build --profile release
	@bin=$$($(FPM) run --profile release flexmbs --runner echo 2>/dev/null | tail -1); \
	OPENBLAS_NUM_THREADS=1 bash inputs/paper/extremes.sh $$bin results/extremes \
	    $(filter-out all,$(VARIANTS))

# A one-node Slurm on this machine (munged, slurmctld, slurmd in a private
# temporary folder, on ports of their own; test/cluster/slurm.sh) runs job
# arrays, a failed and a cancelled task and a dependent job with the debug
# flexmbs, and the quick five-body study by `sweep --slurm --submit`, merged,
# resumed after cancelled tasks (test/cluster/run.sh, well under a minute);
# docs/cluster.md.
.PHONY: test-cluster
test-cluster:
	@$(MAKE) --no-print-directory deps EXTRA_PACKAGES="slurm-wlm munge"
	@FPM="$(FPM)" bash test/cluster/run.sh

# valgrind's memcheck on the debug build (test/memory.sh): one line per
# suite or scene, `N passed, M failed` last; any finding fails.
check-memory:
	@$(MAKE) --no-print-directory deps EXTRA_PACKAGES=valgrind
	@FPM="$(FPM)" bash test/memory.sh

bench: deps
	$(FPM) build --profile release
	bash bench/run.sh
	bash bench/sparse.sh
	bash bench/newton.sh
	bash bench/assemblies.sh
	bash bench/output.sh
	bash bench/mexax_control.sh
	bash bench/modal.sh

# The Python environment of test/vtk_files.py: $(PY_PACKAGES) from PyPI
# (installed once) over the system's Python with its h5py and numpy.
py-venv:
	@if ! $(PY_VENV)/bin/python -c 'import h5py, meshio, vtk' 2>/dev/null || \
	    [ "$$($(PY_VENV)/bin/python -c 'import meshio, vtk; \
	        print(meshio.__version__, vtk.vtkVersion.GetVTKVersion())' 2>/dev/null)" \
	        != "$$(echo '$(PY_PACKAGES)' | sed 's/[a-z]*==//g')" ]; then \
	    echo "installing $(PY_PACKAGES) into $(PY_VENV)"; \
	    /usr/bin/python3 -m venv --system-site-packages $(PY_VENV) && \
	    $(PY_VENV)/bin/pip install --quiet $(PY_PACKAGES) \
	        || { echo "could not install $(PY_PACKAGES)" >&2; exit 1; }; \
	fi

# The API documentation: FORD $(FORD_VERSION) from PyPI in its own virtual
# environment (installed once), its settings in fpm.toml's [extra.ford]
# (sources src/, app/ and legacy/src/; the .F90 files through gfortran's
# preprocessor), HTML into build/docs/api/. FORD reads [extra.ford] from the
# folder of its project file: the project file is standard input, so that
# folder is this one, and the front page is the settings' summary. Any
# warning of FORD fails the target; its output is in build/docs/ford.log.
docs: deps
	@if ! $(FORD_VENV)/bin/ford --version 2>/dev/null | grep -qx "ford version $(FORD_VERSION)"; then \
	    echo "installing FORD $(FORD_VERSION) into $(FORD_VENV)"; \
	    /usr/bin/python3 -m venv $(FORD_VENV) && \
	    $(FORD_VENV)/bin/pip install --quiet ford==$(FORD_VERSION) \
	        || { echo "could not install FORD $(FORD_VERSION)" >&2; exit 1; }; \
	fi
	@mkdir -p $(BUILD)/docs
	@$(FORD_VENV)/bin/ford - < /dev/null > $(BUILD)/docs/ford.log 2>&1 \
	    || { cat $(BUILD)/docs/ford.log; echo "make docs: FORD failed" >&2; exit 1; }
	@if grep -q 'Warning' $(BUILD)/docs/ford.log; then \
	    cat $(BUILD)/docs/ford.log; echo "make docs: FORD warned (above)" >&2; exit 1; \
	fi
	@echo "API documentation: $(BUILD)/docs/api/index.html"

clean:
	rm -rf $(BUILD) legacy/build test/fpm_dependency/build
