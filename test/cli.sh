#!/usr/bin/env bash
# Command-line tests of the flexmbs executable: bad input gives exit 2, a
# message naming file, group, variable and reason, and no output file;
# --help and --version exit 0; a solver failure exits 3 and keeps its HDF5
# file; an unwritable output exits 4; `flexmbs modes` reports its table
# and a spectrum file true to its definitions, with nothing on standard
# error, with or without gnuplot (without it, the plot's test says SKIP).
# The flexible-body example's energy balance: dissipated with viscosity,
# conserved without.
#
#   bash test/cli.sh [path/to/flexmbs]
#
# Without an argument the debug build is used (built if needed). The last
# line is `N passed, M failed`; the exit status is non-zero on failures.
set -u
. "$(dirname "$0")/executable.sh" cli "$@"

work=$(mktemp -d "${TMPDIR:-/tmp}/flexmbs-cli.XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
passed=0
failed=0

pass() { passed=$((passed + 1)); echo "pass cli/$1"; }
fail() { failed=$((failed + 1)); echo "FAIL cli/$1: $2"; }

# check NAME CODE PATTERN [ARGS...]: run, then set $problem to what is
# wrong with the exit code and the output (PATTERN, a fixed string, must be
# in standard error + output); empty when both are right.
check() {
    local code=$2 pattern=$3
    shift 3
    local rc
    output=$("$exe" "$@" 2>&1)
    rc=$?
    problem=""
    if [ "$rc" -ne "$code" ]; then
        problem="exit $rc, expected $code; output: $output"
    elif ! grep -qF -- "$pattern" <<<"$output"; then
        problem="output lacks '$pattern': $output"
    fi
}

# expect NAME CODE PATTERN [ARGS...]: one test of exit code and message.
expect() {
    check "$@"
    if [ -n "$problem" ]; then fail "$1" "$problem"; else pass "$1"; fi
}

# bad NAME PATTERN FILE: exit 2, the message, and no HDF5 file anywhere.
bad() {
    local name=$1 pattern=$2 file=$3
    rm -f ./*.h5 out/*.h5
    check "$name" 2 "$pattern" run "$file" --quiet
    if [ -z "$problem" ] && { compgen -G "*.h5" >/dev/null || compgen -G "out/*.h5" >/dev/null; }
    then
        problem="an output file was created: $(ls ./*.h5 out/*.h5 2>/dev/null)"
    fi
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}

# kept NAME CODE PATTERN FILE ARGS...: exit code, message, and FILE written.
kept() {
    local name=$1 code=$2 pattern=$3 file=$4
    shift 4
    rm -f "$file"
    check "$name" "$code" "$pattern" "$@"
    if [ -z "$problem" ] && [ ! -s "$file" ]; then problem="$file was not written"; fi
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}

mkdir -p out
sim="&simulation problem = 'van_der_pol', t_end = 2 /"
out="&output file = 'out/run.h5' /"

printf '%s\n&solver rtol = 1e-4\n  atoll = 1e-4 /\n%s\n' "$sim" "$out" > unknown_var.nml
bad unknown-variable "unknown_var.nml: &solver: atoll: unknown variable" unknown_var.nml

printf '%s\n&solver max_steps = 1.5 /\n%s\n' "$sim" "$out" > wrong_type.nml
bad wrong-type "wrong_type.nml: &solver: max_steps = 1.5: must be an integer" wrong_type.nml

printf '%s\n&solver rtol = -1e-6 /\n%s\n' "$sim" "$out" > negative_tol.nml
bad negative-tolerance "negative_tol.nml: &solver: rtol = -1e-6: must be positive" \
    negative_tol.nml

bad missing-file "missing.nml: no such file" missing.nml

printf '%s\n&solvers rtol = 1e-4 /\n' "$sim" > unknown_group.nml
bad unknown-group "unknown_group.nml: &solvers: unknown group" unknown_group.nml

# default output name (derived from the input) must not appear either
printf '%s\n&solver rtol = -1 /\n' "$sim" > derived.nml
bad derived-name-not-created "derived.nml: &solver: rtol = -1: must be positive" derived.nml

# an output that is an input of the run, by any spelling: refused with
# exit 2 before anything is written, and the input left as it was
# untouched NAME PATTERN INPUT ARGS...: exit 2, the message, INPUT unchanged.
untouched() {
    local name=$1 pattern=$2 input=$3
    shift 3
    local before
    before=$(md5sum < "$input")
    check "$name" 2 "$pattern" "$@"
    if [ -z "$problem" ] && [ "$(md5sum < "$input")" != "$before" ]; then
        problem="$input was changed"
    fi
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}
mkdir -p in sub
sed -e "s#^&output#\&output file = './clobber.nml',#" "$root/inputs/van_der_pol.nml" \
    > in/clobber.nml
untouched output-is-scene-dot-spelling "would overwrite the input file" in/clobber.nml \
    run in/clobber.nml --quiet
sed -e "s#^&output#\&output file = '../in/clobber2.nml',#" "$root/inputs/van_der_pol.nml" \
    > in/clobber2.nml
untouched output-is-scene-relative-spelling "would overwrite the input file" in/clobber2.nml \
    run "$work/in/clobber2.nml" --quiet
cp "$root/inputs/van_der_pol.nml" in/x.h5
cd in || exit 1
check output-default-is-scene 2 "would overwrite the input file" run ./x.h5 --quiet
cd "$work" || exit 1
if [ -n "$problem" ]; then fail output-default-is-scene "$problem"
elif ! cmp -s in/x.h5 "$root/inputs/van_der_pol.nml"; then
    fail output-default-is-scene "in/x.h5 (the scene) was changed"
else pass output-default-is-scene; fi
cp "$root/inputs/meshes/bar_hex8.mesh" in/bar.mesh
printf '%s\n' "&simulation problem = 'flexible_body', t_end = 0.01 /" \
    "&flexible_body mesh_file = 'in/bar.mesh', fixed = 'clamp' /" \
    "&material youngs_modulus = 7e5, density = 920 /" \
    "&output file = './in/../in/bar.mesh' /" > mesh_clobber.nml
untouched output-is-mesh-file "is the mesh file" in/bar.mesh run mesh_clobber.nml --quiet
# a missing mesh file: the path tried (resolved against the scene's folder) and the line
printf '%s\n' "&simulation problem = 'flexible_body', t_end = 0.01 /" "" \
    "&flexible_body mesh_file = 'nowhere/bar.mesh', fixed = 'clamp' /" \
    "&material youngs_modulus = 7e5, density = 920 /" "&output file = '../out/m.h5' /" > in/no_mesh.nml
bad missing-mesh-file "in/no_mesh.nml: &flexible_body: mesh_file = 'in/nowhere/bar.mesh': in/nowhere/bar.mesh: no such file (line 3)" in/no_mesh.nml

# inertia tensors a body can have: positive definite, principal moments
# satisfying the triangle inequalities (a chain link's was not checked)
sed -e "s/inertia_products = 0.003, 0.002, -0.001/inertia_products = 1.0, 1.0, 1.0/" \
    "$root/inputs/double_pendulum_chain.nml" > chain_inertia.nml
bad chain-inertia-not-definite \
    "chain_inertia.nml: &rigid_chain 'upper': inertia, inertia_products: the inertia tensor is not positive definite" \
    chain_inertia.nml
sed -e "0,/inertia = [0-9., ]*/s//inertia = 0.001, 0.001, 0.01, /" "$root/inputs/four_bar.nml" \
    > triangle.nml
bad rigid-inertia-triangle "violate the triangle inequality J1 + J2 >= J3" triangle.nml
# a moment zero to working precision beside the others (the fuzzer's case:
# 1e-310 overflowed the body's rotational acceleration)
sed -e "0,/inertia = [0-9., ]*/s//inertia = 0.01, 0.01, 1e-310, /" "$root/inputs/four_bar.nml" \
    > singular_inertia.nml
bad rigid-inertia-singular "singular to working precision" singular_inertia.nml

# sizes that cannot fit: counted in 64 bits and against the machine's
# memory before anything is allocated (2000^3 used to overflow and crash)
sed -e "s/divisions = 8, 1, 1/divisions = 2000, 2000, 2000/" \
    "$root/inputs/flexible_cantilever.nml" > huge_mesh.nml
bad huge-mesh-count "divisions = 2000, 2000, 2000: 8.012006E+09 nodes" huge_mesh.nml
sed -e "s/divisions = 8, 1, 1/divisions = 400, 400, 400/" \
    "$root/inputs/flexible_cantilever.nml" > big_mesh.nml
bad big-mesh-memory "divisions = 400, 400, 400: 6.448120E+07 nodes, needs at least ~" big_mesh.nml

# user documentation names only files the repository ships
if grep -nE '\.\./shared|shared/docs|(ALGORITHMS|PAPER|DESIGN|STYLE)\.md' \
        "$root/README.md" "$root"/docs/*.md > outside.txt; then
    fail docs-self-contained "README/docs point outside the repository: $(head -3 outside.txt)"
else pass docs-self-contained; fi

expect help 0 "usage:" --help
expect help-names-command-help 0 "flexmbs COMMAND --help" --help
# `flexmbs help COMMAND` and `flexmbs --help COMMAND` give the command's usage
expect help-command-first 0 "usage: flexmbs columns FILE.h5 COLUMN" help columns
expect help-option-first 0 "usage: flexmbs sweep" --help sweep

# command_help NAME PATTERN OPTIONS ARGS...: a command's own usage
# (app/help_text): exit 0, on standard output only, PATTERN in it, a line
# of its own for each of the space-separated OPTIONS, and not the overview
# of `flexmbs --help` (whose first line no command's usage has)
command_help() {
    local name=$1 pattern=$2 options=$3
    shift 3
    local out rc option
    out=$("$exe" "$@" 2>help.err)
    rc=$?
    problem=""
    if [ "$rc" -ne 0 ]; then problem="exit $rc: $(cat help.err)"
    elif [ -s help.err ]; then problem="standard error: $(cat help.err)"
    elif ! grep -qF -- "$pattern" <<<"$out"; then problem="output lacks '$pattern': $out"
    elif grep -qF -- "- flexible multibody dynamics and stiff DAE solvers" <<<"$out"; then
        problem="the overview of flexmbs --help, not the command's usage"
    fi
    for option in $options; do
        [ -z "$problem" ] && ! grep -qE -- "^  (-[a-z], )?$option( |\$)" <<<"$out" &&
            problem="no line for option $option: $out"
    done
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}
command_help help-run "usage: flexmbs run FILE.nml" "--quiet --verbose --force --help" \
    run --help
command_help help-run-short "usage: flexmbs run FILE.nml" "" run -h
# --help wins over the other arguments, a missing file, a missing value
command_help help-run-among-arguments "usage: flexmbs run FILE.nml" "" run --quiet --help x.nml
command_help help-reference "usage: flexmbs reference STUDY.nml" "--quiet --force --help" \
    reference --help
command_help help-sweep "usage: flexmbs sweep STUDY.nml" \
    "--quiet --force -j --point --merge --slurm --chunk --partition --time --mem --submit --help" \
    sweep --help
command_help help-sweep-missing-value "usage: flexmbs sweep STUDY.nml" "" sweep --chunk --help
command_help help-columns "usage: flexmbs columns FILE.h5 COLUMN" "--help" columns --help
command_help help-columns-with-file "usage: flexmbs columns FILE.h5 COLUMN" "" columns r.h5 -h
command_help help-modes-own "usage: flexmbs modes FILE.nml" \
    "--time --count --method --shift --output --no-run --force --help" modes --help
command_help help-scene-reference "usage: flexmbs scene-reference" "--help" \
    scene-reference --help
expect scene-reference-argument 2 "try 'flexmbs scene-reference --help'" scene-reference x
expect unknown-option-names-command-help 2 "try 'flexmbs run --help'" run x.nml --loud

# flexmbs-bench (an fpm example, bench/bench.f90, built beside flexmbs):
# a wrong command line gives its usage on standard error and exit 2, no
# backtrace; --help the usage on standard output and exit 0
bench=$(dirname "$(readlink -f "$exe")")/../example/flexmbs-bench
# bench_args NAME CODE ARGS...
bench_args() {
    local name=$1 code=$2
    shift 2
    local rc
    problem=""
    if [ ! -x "$bench" ]; then
        fail "$name" "no flexmbs-bench beside $exe ($bench)"
        return
    fi
    "$bench" "$@" > bench.out 2> bench.err
    rc=$?
    local usage=bench.err quiet=bench.out
    [ "$code" -eq 0 ] && usage=bench.out quiet=bench.err
    if [ "$rc" -ne "$code" ]; then problem="exit $rc, expected $code: $(cat bench.err)"
    elif ! grep -q '^usage: flexmbs-bench' "$usage"; then
        problem="no usage in $usage: $(cat bench.out bench.err)"
    elif [ -s "$quiet" ]; then problem="$quiet is not empty: $(cat "$quiet")"
    elif grep -qiE 'backtrace|error termination|error stop|runtime error' bench.err; then
        problem="$(cat bench.err)"
    fi
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}
bench_args bench-no-arguments 2
bench_args bench-too-few-arguments 2 radau5 vdp 2
bench_args bench-not-a-number 2 radau5 vdp x dense
bench_args bench-unknown-problem 2 radau5 vdpp 2 dense
bench_args bench-unknown-integrator 2 fly vdp 2 dense
bench_args bench-bad-tolerance 2 radau5 vdp 2 dense 100 -1
bench_args bench-sparse-lu-short 2 sparse_lu hex 3
bench_args bench-help 0 --help
expect version 0 "flexmbs 0." --version
# the version its files carry (core/version) is fpm.toml's
expect version-is-fpm-toml 0 "flexmbs $(sed -n 's/^version = "\(.*\)"/\1/p' "$root/fpm.toml")" \
    --version
expect no-arguments 2 "usage:"
expect unknown-command 2 "unknown command 'fly'" fly
expect unknown-option 2 "unknown option '--loud'" run x.nml --loud

# success: exit 0, statistics and final state printed, file written
printf '%s\n&solver rtol = 1e-4, atol = 1e-4, h0 = 1e-6 /\n%s\n' "$sim" "$out" > ok.nml
kept success 0 "y(1) =  1.7061611" out/run.h5 run ok.nml --quiet
kept success-statistics 0 "radau5: NST=275 NAC=238" out/run.h5 run ok.nml --quiet
# NRJ by cause on the statistics line, in the HDF5 attributes and, asked
# for, in the table (docs/solvers.md, Rejection causes)
kept success-causes 0 "NRJ=37 (error test 8, Newton slow 29) NFE=2218" out/run.h5 \
    run ok.nml --quiet
if problem=$(/usr/bin/python3 - out/run.h5 2>&1 <<'PY'
import sys, h5py
a = h5py.File(sys.argv[1], 'r').attrs
causes = ['NRJ_ERROR_TEST', 'NRJ_NEWTON_DIVERGED', 'NRJ_NEWTON_SLOW', 'NRJ_SINGULAR',
          'NRJ_REFUSED', 'NRJ_PROJECTION', 'NRJ_UNSTABLE']
values = [int(a[c]) for c in causes]
assert sum(values) == int(a['NRJ']) == 37, values
assert values == [8, 0, 29, 0, 0, 0, 0], values
assert 'refusal' not in a
t = h5py.File(sys.argv[1], 'r')['time']
assert t.attrs['unit'] == 's', t.attrs.get('unit')
assert 'description' in t.attrs
PY
); then pass hdf5-rejection-causes; else fail hdf5-rejection-causes "$problem"; fi
printf '%s\n&solver rtol = 1e-4, atol = 1e-4, h0 = 1e-6 /\n%s\n' "$sim" \
    "&output file = 'out/run.h5', table = 'out/run.csv', reasons = .true. /" > reasons.nml
kept table-rejection-causes 0 "radau5: NST=275" out/run.csv run reasons.nml --quiet
if ! grep -q '^solver,.*,NSOL,error test,Newton diverged,Newton slow,singular,refused,projection,unstable$' out/run.csv \
    || ! grep -q ',37,248,.*,8,0,29,0,0,0,0$' out/run.csv; then
    fail table-rejection-columns "$(cat out/run.csv)"
else pass table-rejection-columns; fi
printf '%s\n&solver name = '"'ida'"', rtol = 1e-8, atol = 1e-8 /\n%s\n' "$sim" "$out" > ida.nml
kept success-ida 0 "y(1) =  1.70616" out/run.h5 run ida.nml --quiet

# the BDF codes refuse coordinate projection before anything is written
# (IDA used to leave it out silently: NPRJ = 0)
for solver in ddassl ida; do
    sed -e "s/formulation = 'ggl'/formulation = 'index2', projection = .true./" \
        -e "s/^\( *name *= *\)'radau5'/\1'$solver'/" "$root/inputs/four_bar.nml" \
        > "projection_$solver.nml"
    bad "$solver-refuses-projection" "$solver: projection is refused" "projection_$solver.nml"
done

# DDASSL on the index-3 pendulum: accepted, with a warning (docs/theory.md, 3.6)
printf "&simulation problem = 'pendulum', pendulum_formulation = 'index3', t_end = 1 /\n&solver name = 'ddassl', rtol = 1e-5, atol = 1e-5 /\n%s\n" "$out" > index3.nml
kept ddassl-index3-warning 0 "warning: ddassl: the problem has index-3 components" out/run.h5 \
    run index3.nml --quiet

# solver failure: exit 3, reason, time reached, statistics, file kept
printf '%s\n&solver max_steps = 5 /\n%s\n' "$sim" "$out" > fails.nml
kept solver-failure 3 "maximum number of steps" out/run.h5 run fails.nml --quiet
kept solver-failure-statistics 3 "statistics so far: NST=" out/run.h5 run fails.nml --quiet

# energy NAME MODE: the energies the last run printed,
#   energy at t_start [J]: strain, kinetic, total  S0 K0 E0
#   energy at t_end   [J]: strain, kinetic, total  S K E1,
# against physics, in units of the scene's rtol = 1e-5 times the energy
# exchanged, S + K (0.67 J damped, 0.71 J undamped). MODE conserved (no
# viscosity): |E1 - E0| <= 2 rtol (S + K) (measured without viscosity:
# RADAU5 0.11, IDA 0.12, DDASSL 1.1, MEXAX 0.003 of rtol (S + K)). MODE
# damped: the viscous body dissipates, E0 - E1 > 100 rtol (S + K) = 6.7e-4
# J (measured 0.0249 J with every solver, 3.7 % of S + K); that the energy
# does not grow is not enough, a lost damping force would pass it. Sets
# $change (E1 - E0).
energy() {
    local name=$1 mode=$2 verdict
    verdict=$(awk -v mode="$mode" -v rtol=1e-5 '
        /^energy at t_start +\[J\]:/ { e0 = $NF; n++ }
        /^energy at t_end +\[J\]:/ { s = $(NF - 2); k = $(NF - 1); e1 = $NF; n++ }
        END {
            if (n != 2) { print "FAIL - no energy lines"; exit }
            unit = rtol * (s + k); change = e1 - e0
            if (mode == "damped" && !(-change > 100 * unit)) problem = ", not dissipated"
            if (mode == "conserved" && !(change <= 2 * unit && -change <= 2 * unit))
                problem = ", not conserved"
            printf "%s %.6e energy change %.6e J = %.3g rtol (S + K)%s\n", \
                (problem == "" ? "ok" : "FAIL"), change, change, change / unit, problem
        }' <<<"$output")
    change=$(cut -d' ' -f2 <<<"$verdict")
    echo "  $name: ${verdict#* * }"
    if [ "${verdict%% *}" = ok ]; then pass "$name"
    else fail "$name" "${verdict#* * }: $(grep '^energy' <<<"$output")"; fi
}

# the flexible-body example with every solver: exit 0, statistics, energies
# (damped: dissipated, by every solver the same to 10 rtol (S + K) = 6.7e-5
# J, measured spread 3.0e-5 J); without viscosity (RADAU5): conserved
example="$root/inputs/flexible_cantilever.nml"
changes=""
for solver in radau5 ddassl ida mexax; do
    sed "s/name = 'radau5'/name = '$solver'/" "$example" > "cantilever_$solver.nml"
    kept "flexible-body-$solver" 0 "$solver: NST=" "cantilever_$solver.h5" \
        run "cantilever_$solver.nml" --quiet
    energy "flexible-body-energy-$solver" damped
    changes="$changes $change"
done
spread=$(tr ' ' '\n' <<<"$changes" | awk 'NF { n++; if (n == 1 || $1 < lo) lo = $1; if (n == 1 || $1 > hi) hi = $1 }
    END { if (n == 4) printf "%.3e", hi - lo }')
if [ -n "$spread" ] && awk -v d="$spread" 'BEGIN { exit !(d <= 6.7e-5) }'; then
    echo "  flexible-body-energy-solvers-agree: spread $spread J"
    pass flexible-body-energy-solvers-agree
else
    fail flexible-body-energy-solvers-agree "energy changes$changes: spread '$spread' J, more than 6.7e-5 J"
fi
sed -e "s/viscosity *= *[0-9.eE+-]*/viscosity = 0.0/" "$example" > cantilever_undamped.nml
kept flexible-body-undamped 0 "radau5: NST=" cantilever_undamped.h5 run cantilever_undamped.nml --quiet
energy flexible-body-energy-conserved conserved

# bad flexible-body input: exit 2 before any file exists
sed "s/fixed     = 'xmin'/fixed = 'xmim'/" "$example" > bad_set.nml
bad flexible-body-unknown-set "bad_set.nml: &flexible_body: fixed = 'xmim': mesh: no node set named 'xmim' (did you mean 'xmin'?)" \
    bad_set.nml
fb="&simulation t_end = 0.01 /"
mat="&material youngs_modulus = 7e5, density = 920 /"
printf "%s\n&flexible_body lengths = 1, 1, 1, divisions = 2, 1 /\n%s\n" "$fb" "$mat" > fb_count.nml
bad flexible-body-array-count "fb_count.nml: &flexible_body: divisions = 2, 1: needs 3 values (line 2)" \
    fb_count.nml
printf "%s\n&flexible_body lengths = 1, 1, 1 /\n" "$fb" > fb_nomat.nml
bad material-missing "fb_nomat.nml: &flexible_body: needs a &material group" fb_nomat.nml
printf "%s\n&flexible_body lengths = 1, 1, 1 /\n%s\n&material youngs_modulus = -1, density = 1, elements = 'all' /\n" \
    "$fb" "$mat" > fb_young.nml
bad material-negative-modulus "fb_young.nml: &material: youngs_modulus = -1: must be positive (line 4)" \
    fb_young.nml
printf "%s\n&flexible_body lengths = 1, 1, 1, divisions = 2, 1, 1 /\n&material youngs_modulus = 1, density = 1, elements = 'xmax_layer' /\n" \
    "$fb" > fb_cover.nml
bad material-not-covering "fb_cover.nml: &material: elements: element 1 has no material" fb_cover.nml

# a missing output folder is bad input, found while reading; a folder that
# exists but cannot be written is an I/O error
printf "%s\n&output file = 'no/such/dir/x.h5' /\n" "$sim" > no_folder.nml
bad output-no-folder "&output: file = 'no/such/dir/x.h5': the folder 'no/such/dir/' does not exist" \
    no_folder.nml
printf "%s\n&output vtk = 'nodir/p', file = 'none' /\n" "$sim" > no_vtk_folder.nml
bad vtk-no-folder "&output: vtk = 'nodir/p': the folder 'nodir/' does not exist" no_vtk_folder.nml
printf "%s\n&output vtk = 'p', vtk_format = 'raw', file = 'none' /\n" "$sim" > vtk_format.nml
bad vtk-format-choices "&output: vtk_format = 'raw': must be 'binary' or 'ascii'" vtk_format.nml
printf "%s\n&output file = '/dev/full' /\n" "$sim" > io_error.nml
expect io-error 4 "/dev/full: HDF5 cannot create the file" run io_error.nml --quiet --force
mkdir -p out/folder
printf "%s\n&output file = 'out/folder' /\n" "$sim" > out_folder.nml
bad output-is-folder "'out/folder' exists and is a folder" out_folder.nml
sed -e "s#^&output#\&output table = 'table.md',#" "$root/inputs/van_der_pol.nml" > table.md
untouched table-is-scene "&output: table: 'table.md' is the scene file itself: refused" table.md run table.md --quiet
printf "%s\n&output table = 'no/dir/t.md' /\n" "$sim" > table_folder.nml
bad table-no-folder "&output: table = 'no/dir/t.md': the folder 'no/dir/' does not exist" \
    table_folder.nml

# A driven four-bar (inputs/four_bar.nml) with every solver
for s in radau5 ddassl ida mexax; do
    sed -e "s/name = 'radau5'/name = '$s'/" -e "s/^&output/\&output file = 'out\/run.h5',/" \
        "$root/inputs/four_bar.nml" > "fourbar_$s.nml"
    kept "multibody-$s" 0 "$s: NST=" out/run.h5 run "fourbar_$s.nml" --quiet
done
sed -e "s/marker_i = 'B1', marker_j = 'B2'/marker_i = 'B1', marker_j = 'B9'/" \
    "$root/inputs/four_bar.nml" > fourbar_bad.nml
bad multibody-unknown-marker "fourbar_bad.nml: &joint: marker_j = 'B9': no &marker of that name" \
    fourbar_bad.nml

# The four-bar with its crank as a chain inside the system
sed -e "s/^&output/\&output file = 'out\/run.h5',/" "$root/inputs/four_bar_chain.nml" \
    > fourbar_chain.nml
kept "multibody-with-chain" 0 "radau5: NST=" out/run.h5 run fourbar_chain.nml --quiet

# A rigid chain in relative coordinates (inputs/double_pendulum_chain.nml)
for s in radau5 ddassl ida mexax; do
    sed -e "s/name = 'radau5'/name = '$s'/" -e "s/^&output/\&output file = 'out\/run.h5',/" \
        "$root/inputs/double_pendulum_chain.nml" > "chain_$s.nml"
    kept "rigid-chain-$s" 0 "$s: NST=" out/run.h5 run "chain_$s.nml" --quiet
done

# A rigid link with a soft bar attached (inputs/rigid_flexible_pendulum.nml)
for s in radau5 ddassl; do
    sed -e "s/name = 'radau5'/name = '$s'/" -e "s/^&output/\&output file = 'out\/run.h5',/" \
        "$root/inputs/rigid_flexible_pendulum.nml" > "rigidflex_$s.nml"
    kept "rigid-flexible-$s" 0 "$s: NST=" out/run.h5 run "rigidflex_$s.nml" --quiet
done
sed -e "s/node_set = 'xmin'/node_set = 'xmn'/" "$root/inputs/rigid_flexible_pendulum.nml" \
    > rigidflex_bad.nml
bad rigid-flexible-unknown-set "rigidflex_bad.nml: &joint 'root': marker_j 'root': mesh: no node set named 'xmn'" \
    rigidflex_bad.nml

# A rigid link hinged to the face of a soft cantilever (inputs/face_hinge.nml:
# a revolute joint on a node-set marker, through a node frame)
for s in radau5 ida mexax; do
    sed -e "s/name = 'radau5'/name = '$s'/" -e "s/^&output/\&output file = 'out\/run.h5',/" \
        "$root/inputs/face_hinge.nml" > "hinge_$s.nml"
    kept "face-hinge-$s" 0 "$s: NST=" out/run.h5 run "hinge_$s.nml" --quiet
done

# The five-body mechanism (inputs/five_body.nml), its first instants
for s in radau5 mexax; do
    sed -e "s/name = 'radau5'/name = '$s'/" -e "s/^&output/\&output file = 'out\/run.h5',/" \
        -e "s/t_end   = 1.0 /t_end   = 0.02 /" "$root/inputs/five_body.nml" > "five_$s.nml"
    kept "five-body-$s" 0 "$s: NST=" out/run.h5 run "five_$s.nml" --quiet
done
# a successful run says nothing on standard error (a plain STOP added
# gfortran's note on the floating-point flags still raised)
errors=$("$exe" run five_radau5.nml --quiet 2>&1 >/dev/null)
if [ -z "$errors" ]; then pass quiet-success; else fail quiet-success "$errors"; fi

# What factored the Newton matrices, printed and in the file's attribute
# linear_solver, as 'auto' decides (docs/linear_algebra.md): the five-body's
# condensed matrix S has order 221 < 500, so KLU; the full path's 547
# unknowns have fill < 10, KLU; IDA's full path is SUNDIALS' KLU; van der
# Pol has 2 unknowns, dense; MEXAX factors its augmented systems by the
# structure of M; MUMPS when asked, with the ordering its analysis used.
linear_solver_case() {  # NAME SCENE EXPECTED [SED]
    sed -e "s/^&output/\&output file = 'out\/ls.h5',/" -e "${4:-}" "$2" > "ls_$1.nml"
    rm -f out/ls.h5
    check "linear-solver-$1" 0 "linear solver: $3" run "ls_$1.nml" --quiet
    if [ -z "$problem" ]; then
        problem=$(/usr/bin/python3 - out/ls.h5 "$3" 2>&1 <<'PY'
import sys, h5py
got = h5py.File(sys.argv[1], 'r').attrs['linear_solver']
got = got.decode() if isinstance(got, bytes) else got
if not got.startswith(sys.argv[2]):
    print(f"attribute linear_solver = {got!r}, expected {sys.argv[2]!r}...")
PY
        )
    fi
    if [ -n "$problem" ]; then fail "linear-solver-$1" "$problem"; else pass "linear-solver-$1"; fi
}
short="s/t_end   = 1.0 /t_end   = 0.01 /"
linear_solver_case condensed "$root/inputs/five_body.nml" "condensed klu, ordering amd" "$short"
linear_solver_case condensed-mumps "$root/inputs/five_body.nml" "condensed mumps, ordering " \
    "$short; s/^&solver/\&solver linear_solver = 'mumps',/"
linear_solver_case full "$root/inputs/five_body.nml" "klu, ordering amd" \
    "$short; s/^&solver/\&solver newton_system = 'full',/"
linear_solver_case ida-full "$root/inputs/five_body.nml" "klu (SUNDIALS)" \
    "$short; s/name = 'radau5'/name = 'ida'/; s/^&solver/\&solver newton_system = 'full',/"
linear_solver_case mexax "$root/inputs/five_body.nml" "structured [M Gt; G 0]" \
    "$short; s/name = 'radau5'/name = 'mexax'/"
linear_solver_case dense "$root/inputs/van_der_pol.nml" "dense" "s/t_end *= *[0-9.e+]*/t_end = 0.1/"

# Studies: a reference with its cross-check, a sweep against it, bad input
sed -e "s#scene               = '../four_bar.nml'#scene = '$root/inputs/four_bar.nml'#" \
    -e "s/solvers             = 'radau5', 'ddassl', 'ida', 'mexax'/solvers = 'radau5', 'mexax'/" \
    "$root/inputs/paper/four_bar_study.nml" > study.nml
expect study-reference 0 "written: study_reference.h5" reference study.nml --quiet
expect study-sweep 0 "6 runs finished, 0 failed" sweep study.nml --quiet
# in two processes: the same table, the CPU column apart
"$exe" sweep study.nml --quiet 2>&1 | grep '^|' | cut -d'|' -f1-9,11- > serial.txt
"$exe" sweep study.nml -j 2 --quiet 2>&1 | grep '^|' | cut -d'|' -f1-9,11- > parallel.txt
if [ -s serial.txt ] && cmp -s serial.txt parallel.txt; then pass study-sweep-parallel
else fail study-sweep-parallel "tables differ: $(diff serial.txt parallel.txt | head -5)"; fi
# components of a trajectory as text columns
expect columns 0 "1.000000000000000E+000" columns study_reference.h5 1 2
expect columns-range 2 "component 999 outside 1 .. " columns study_reference.h5 999
printf "&study scene = 'x.nml', solvers = 'rk4' /\n" > bad_study.nml
expect study-bad 2 "bad_study.nml: &study: solvers = 'rk4': must be one of" sweep bad_study.nml
# a study's outputs: never one of its inputs, and their folder checked
# before the reference is computed (it used to be refused only when written)
cp "$root/inputs/four_bar.nml" own_scene.nml
printf "&study scene = 'own_scene.nml', reference_file = './own_scene.nml' /\n" > clobber_study.nml
untouched study-reference-is-scene "is an input of the study" own_scene.nml \
    reference clobber_study.nml --quiet
printf "&study scene = '%s/inputs/four_bar.nml', reference_file = 'nodir/r.h5' /\n" "$root" \
    > nodir_study.nml
expect study-reference-no-folder 2 "the folder 'nodir' does not exist" reference nodir_study.nml \
    --quiet
printf "&study scene = '%s/inputs/four_bar.nml', reference_file = 'none.h5' /\n" "$root" \
    > no_reference.nml
expect study-no-reference 2 "no reference file (make it with flexmbs reference no_reference.nml first)" \
    sweep no_reference.nml --quiet

# A reference carries the fingerprint of what made it (the scene's settings,
# its mesh, t_start, t_end, the output times, the reference's solver and
# tolerance): every kind of sweep refuses one of another study (exit 2,
# nothing written), naming what differs and the command that remakes it;
# --force uses it and the table says so.
cp "$root/inputs/four_bar.nml" fp_scene.nml
printf "&study scene = 'fp_scene.nml', table = 'fp.md', reference_tolerance = 1e-6,
  check_solver = 'none', solvers = 'radau5', stabilisations = 'ggl', tolerances = 1e-3, 1e-4 /\n" \
    > fp.nml
expect fingerprint-reference 0 "written: fp_reference.h5" reference fp.nml --quiet
expect fingerprint-unchanged 0 "2 runs finished, 0 failed" sweep fp.nml --quiet
rm -f fp.md
# the motor twice as fast (and a comment, which changes nothing)
sed -i -e 's/coefficients = 0.3, 6.283185307179586/coefficients = 0.3, 12.566370614359172/' \
    -e '1s/^/! twice as fast\n/' fp_scene.nml
# refused: sweep PATTERN ARGS...: exit 2, PATTERN and the command, no table,
# no record, no Slurm script
refused() {
    local name=$1 pattern=$2
    shift 2
    rm -rf fp_points fp.md
    check "$name" 2 "$pattern" sweep fp.nml "$@"
    if [ -z "$problem" ] && ! grep -qF "remake it: flexmbs reference fp.nml (or use it as it is: --force)" <<<"$output"; then
        problem="no command that remakes it: $output"
    elif [ -z "$problem" ] && { [ -e fp.md ] || compgen -G "fp_points/*" > /dev/null; }; then
        problem="written: $(ls fp.md fp_points 2>&1)"
    fi
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}
scene_changed="what differs: the scene text (after defaults): &driver(1) coefficients = 0.3, 6.283185307179586, 0, 0 in the reference, 0.3, 12.566370614359172, 0, 0 now"
refused fingerprint-scene "fp_reference.h5 was not made from the study as it is now; $scene_changed" --quiet
refused fingerprint-point "$scene_changed" --point 1 --quiet
refused fingerprint-merge "$scene_changed" --merge
refused fingerprint-slurm "$scene_changed" --slurm
refused fingerprint-jobs "$scene_changed" -j 2 --quiet
note="note: the reference fp_reference.h5 is stale (it differs in the scene text), used as it is (--force)"
check fingerprint-force 0 "$note" sweep fp.nml --quiet --force
if [ -z "$problem" ] && ! grep -qxF "$note" fp.md; then problem="fp.md lacks the note: $(cat fp.md)"; fi
if [ -n "$problem" ]; then fail fingerprint-force "$problem"; else pass fingerprint-force; fi
check fingerprint-force-jobs 0 "$note" sweep fp.nml -j 2 --quiet --force
if [ -z "$problem" ] && ! grep -q "2 runs finished, 0 failed" <<<"$output"; then problem="$output"; fi
if [ -n "$problem" ]; then fail fingerprint-force-jobs "$problem"; else pass fingerprint-force-jobs; fi
expect fingerprint-force-slurm 0 "$note" sweep fp.nml --slurm --force
if grep -q -- '--point "$k" --quiet --force ' fp_points/array.sbatch && grep -q -- ' --merge --force$' \
    fp_points/merge.sbatch; then pass fingerprint-force-slurm-scripts
else fail fingerprint-force-slurm-scripts "$(cat fp_points/*.sbatch)"; fi
# another t_end: refused, and with --force too, since the output times differ
cp "$root/inputs/four_bar.nml" fp_scene.nml
sed -i 's/t_end   = 1.0 /t_end   = 0.5 /' fp_scene.nml
refused fingerprint-t-end "what differs: t_end (1 in the reference, 0.5 now); the output times (101 from 0 to 1 s in the reference, 101 from 0 to 0.5 s now)" --quiet
check fingerprint-t-end-force 2 "the output times of the scene (101 from 0 to 0.5 s) are not those of the reference fp_reference.h5 (101 from 0 to 1 s)" \
    sweep fp.nml --quiet --force
if [ -n "$problem" ]; then fail fingerprint-t-end-force "$problem"; else pass fingerprint-t-end-force; fi
# the reference's tolerance is part of it
cp "$root/inputs/four_bar.nml" fp_scene.nml
sed -i 's/reference_tolerance = 1e-6/reference_tolerance = 1e-7/' fp.nml
refused fingerprint-tolerance "what differs: reference_tolerance (1E-6 in the reference, 1E-7 now)" --quiet
sed -i 's/reference_tolerance = 1e-7/reference_tolerance = 1e-6/' fp.nml
expect fingerprint-restored 0 "2 runs finished, 0 failed" sweep fp.nml --quiet
# a reference of an older flexmbs, without a fingerprint
/usr/bin/python3 - fp_reference.h5 <<'PY'
import sys, h5py
a = h5py.File(sys.argv[1], 'r+').attrs
for k in ('reference_fingerprint', 'reference_fingerprint_parts', 'reference_scene_settings'):
    del a[k]
PY
refused fingerprint-none "fp_reference.h5 has no fingerprint: it predates reference fingerprints" --quiet
expect fingerprint-none-force 0 "note: the reference fp_reference.h5 is stale (predates reference fingerprints), used as it is (--force)" \
    sweep fp.nml --quiet --force

# Points alone, merges and Slurm scripts (docs/studies_on_a_cluster.md).
# The -j 2 sweep above left every point's record in study_points/.
if [ "$(ls study_points/point_*.rec 2>/dev/null | wc -l)" -eq 6 ] \
    && grep -qx 'outcome = ok' study_points/point_6.rec; then pass sweep-records
else fail sweep-records "study_points: $(ls study_points 2>&1)"; fi
expect sweep-merge 0 "6 runs finished, 0 failed" sweep study.nml --merge
"$exe" sweep study.nml --merge 2>&1 | grep '^|' | cut -d'|' -f1-9,11- > merged.txt
if [ -s merged.txt ] && cmp -s serial.txt merged.txt; then pass sweep-merge-as-serial
else fail sweep-merge-as-serial "tables differ: $(diff serial.txt merged.txt | head -5)"; fi
expect sweep-point 0 "record: study_points/point_2.rec" sweep study.nml --point 2 --quiet
expect sweep-point-beyond 2 "study.nml: --point 7: the grid has points 1 .. 6" \
    sweep study.nml --point 7
# a study without records: every point missing, the commands for each, exit 3
# (its reference is study.nml's: the same scene, solver and tolerance)
sed "s/^&study/\&study reference_file = 'study_reference.h5',/" study.nml > empty.nml
check sweep-merge-empty 3 "missing: 6 of 6 points have no current record in empty_points: 1-6" \
    sweep empty.nml --merge
for k in 1 2 3 4 5 6; do
    [ -z "$problem" ] && ! grep -q -- "^resubmit: .* sweep $work/empty.nml --point $k\$" <<<"$output" \
        && problem="no resubmit line for point $k: $output"
done
if [ -n "$problem" ]; then fail sweep-merge-empty "$problem"; else pass sweep-merge-empty; fi
# a record of another text of the study (a comment changed) is stale, missing
sed -i '1s/^/! another comment\n/' empty.nml
mkdir -p empty_points && cp study_points/point_3.rec empty_points/point_3.rec
expect sweep-merge-stale 3 "stale: point 3: computed from another text of the study file" \
    sweep empty.nml --merge
# options
expect sweep-chunk-zero 2 "--chunk 0: needs a whole number >= 1" sweep study.nml --slurm --chunk 0
expect sweep-chunk-text 2 "--chunk x: needs a whole number >= 1" sweep study.nml --slurm --chunk x
expect sweep-time-bad 2 "--time '1:75': needs a Slurm time limit" sweep study.nml --slurm --time 1:75
expect sweep-mem-bad 2 "--mem '2GB': needs a whole number" sweep study.nml --slurm --mem 2GB
expect sweep-slurm-point 2 "sweep: --point --slurm: only one of" sweep study.nml --slurm --point 1
expect sweep-slurm-jobs 2 "sweep: -j --slurm: only one of" sweep study.nml --slurm -j 2
expect sweep-merge-jobs 2 "sweep: -j --merge: only one of" sweep study.nml --merge -j 2
expect sweep-submit-alone 2 "--submit: only with --slurm" sweep study.nml --submit
expect sweep-chunk-alone 2 "--chunk: only with --slurm" sweep study.nml --chunk 2
expect sweep-slurm-unknown 2 "unknown option '--nodes'" sweep study.nml --slurm --nodes 2
expect sweep-slurm-no-reference 2 "no reference file" sweep no_reference.nml --slurm
# the scripts: 6 points in tasks of 4 are the array 1-6:4 (2 tasks)
expect sweep-slurm-scripts 0 "(6 points in 2 tasks)" sweep study.nml --slurm --chunk 4 \
    --time 0:10:00 --mem 1G --partition test
a=study_points/array.sbatch
if grep -qx '#SBATCH --array=1-6:4' $a && grep -qx '#SBATCH --cpus-per-task=1' $a \
    && grep -qx '#SBATCH --time=0:10:00' $a && grep -qx '#SBATCH --mem=1G' $a \
    && grep -qx '#SBATCH --partition=test' $a \
    && grep -qx "#SBATCH --output=$work/study_points/slurm_%A_%a.out" $a \
    && grep -qx "study='$work/study.nml'" $a && grep -qx "exe='$exe'" $a \
    && grep -q -- ' --merge$' study_points/merge.sbatch; then pass sweep-slurm-array
else fail sweep-slurm-array "$(cat $a study_points/merge.sbatch 2>&1)"; fi
# its tasks' points: the script run by hand with a stand-in for flexmbs
printf '#!/bin/sh\necho "$4" >> %s/ran.txt\n' "$work" > stand_in.sh && chmod +x stand_in.sh
sed "s#^exe=.*#exe='$work/stand_in.sh'#" $a > stand_in.sbatch
ran() { rm -f ran.txt; SLURM_ARRAY_TASK_ID=$1 bash stand_in.sbatch ${2:+"$2"}; tr '\n' ' ' < ran.txt; }
got="$(ran 1)/$(ran 5)/$(ran 2 1)"
if [ "$got" = "1 2 3 4 /5 6 /2 " ]; then pass sweep-slurm-task-points
else fail sweep-slurm-task-points "tasks 1, 5 and 2 (alone) ran '$got'"; fi

# SIGTERM or SIGINT to a parallel sweep: its points stop after their step,
# no table, exit 143 / 130, no point left running. The points (MEXAX at
# tight tolerances over 0.3 s) take far longer than the test waits.
sed -e "s#'../five_body.nml'#'$root/inputs/five_body.nml'#" -e "s#t_end               = 0.05#t_end = 0.3#" \
    -e "s#'../../build/five_body_quick_reference.h5'#'sig_reference.h5', table = 'sig.md'#" \
    -e "s#reference_tolerance = 1.0e-9#reference_tolerance = 1e-4#" -e "s#check_solver        = 'ddassl'#check_solver = 'none'#" \
    -e "s#solvers             = 'ddassl', 'radau5', 'mexax'#solvers = 'mexax'#" \
    -e "s#tolerances          = 1.0e-4, 1.0e-6#tolerances = 1e-6, 1e-7#" \
    "$root/inputs/paper/five_body_quick.nml" > sig.nml
"$exe" reference sig.nml --quiet > /dev/null 2>&1 || fail sweep-signal-reference "$(cat sig.nml)"
for sig in TERM INT; do
    rm -rf sig_points sig.md
    [ $sig = INT ] && set -m   # a job of its own: SIGINT not ignored, as at a terminal
    # SIGINT ignored by whoever started this script (a background job of a
    # non-interactive shell) stays ignored in every child, and the shell
    # cannot reset it: restore the default disposition before the sweep.
    python3 -c 'import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL);
os.execv(sys.argv[1], sys.argv[1:])' "$exe" sweep sig.nml -j 2 --quiet > sig.out 2>&1 &
    pid=$!
    set +m
    # until both points have computed for a second (they have caught the
    # signals long before)
    deadline=$(( $(date +%s) + 60 ))
    until [ "$(date +%s)" -ge "$deadline" ]; do
        busy=0
        for c in $(pgrep -P $pid); do [ "$(ps -o times= -p "$c")" -ge 1 ] 2>/dev/null && busy=$((busy + 1)); done
        [ $busy -eq 2 ] && break
        sleep 0.1
    done
    kids=$(pgrep -P $pid)
    if [ $sig = INT ]; then kill -INT -- -$pid; else kill -TERM $pid; fi
    wait $pid
    rc=$?
    want=$([ $sig = INT ] && echo 130 || echo 143)
    left=""
    for c in $kids; do kill -0 "$c" 2>/dev/null && left="$left $c"; done
    if [ "$rc" = "$want" ] && grep -q "stopped by SIG$sig" sig.out && [ ! -e sig.md ] \
        && [ -z "$left" ] && ! compgen -G "sig_points/*.rec" > /dev/null \
        && grep -q "point 1: stopped by SIG$sig; no record written" sig_points/point_1.log \
        && grep -q "point 2: stopped by SIG$sig; no record written" sig_points/point_2.log; then
        pass sweep-parallel-sig$sig
    else
        fail sweep-parallel-sig$sig "exit $rc (want $want), still running: '$left', $(ls sig_points 2>&1): $(cat sig.out sig_points/*.log)"
    fi
done

# ParaView output of a flexible body beside a rigid one (as text: the checks
# below read the XML; test/vtk_files.py reads the binary default with VTK)
sed -e "s/t_end   = 0.5 /t_end   = 0.02 /" \
    -e "s#^&output#\&output vtk = 'out/vis', vtk_format = 'ascii', file = 'none',#" \
    -e "s/n_output = 51/n_output = 3/" "$root/inputs/rigid_flexible_pendulum.nml" > vis.nml
expect vtk-run 0 "radau5: NST=" run vis.nml --quiet
if [ -f out/vis_0002.vtu ] && [ -f out/vis_bodies_0002.vtu ] && [ -f out/vis_joints_0002.vtu ] && \
   [ "$(grep -c '<DataSet' out/vis.pvd)" -eq 9 ] && \
   grep -q 'NumberOfPoints="20" NumberOfCells="4"' out/vis_0002.vtu && \
   grep -q 'Name="von_mises"' out/vis_0002.vtu; then pass vtk-files
else fail vtk-files "$(ls out; head -c 400 out/vis.pvd 2>/dev/null)"; fi
# a chain's links beside the rigid bodies (two bodies and a one-link chain)
sed -e "s/t_end   = 1.0 /t_end   = 0.02 /" -e "s#^&output#\&output vtk = 'out/chain', file = 'none',#" \
    -e "s/n_output = 101/n_output = 2/" "$root/inputs/four_bar_chain.nml" > chain_vtk.nml
expect vtk-chain-run 0 "radau5: NST=" run chain_vtk.nml --quiet
if grep -q 'NumberOfPoints="3" NumberOfCells="3"' out/chain_bodies_0001.vtu 2>/dev/null; then
    pass vtk-chain-links
else fail vtk-chain-links "$(head -c 300 out/chain_bodies_0001.vtu 2>/dev/null)"; fi
# the bodies by name: field data body_names (a UInt8 array, which meshio
# reads: character codes, 0 after each name) and point data body_id; 'link'
# is 108 105 110 107
if grep -q 'type="UInt8" Name="body_names" NumberOfTuples="5"' out/vis_bodies_0002.vtu 2>/dev/null &&
    grep -qx ' 108 105 110 107 0' out/vis_bodies_0002.vtu && grep -q 'Name="body_id"' \
    out/vis_bodies_0002.vtu; then pass vtk-bodies-named
else fail vtk-bodies-named "$(grep -A2 FieldData out/vis_bodies_0002.vtu 2>/dev/null)"; fi
# the .pvd's times are the HDF5 file's /time to the last bit (17 digits: at t_end =
# 0.011 and 4 outputs, 0.0036666666666666666 needs all of them)
sed -e "s/t_end   = 0.5 /t_end   = 0.011 /" \
    -e "s#^&output#\&output vtk = 'out/vt', vtk_format = 'ascii', file = 'out/vt.h5',#" \
    -e "s/n_output = 51/n_output = 4/" "$root/inputs/rigid_flexible_pendulum.nml" > vt.nml
expect vtk-times-run 0 "radau5: NST=" run vt.nml --quiet
if /usr/bin/python3 - out/vt.pvd out/vt.h5 <<'PY'
import re, sys, h5py
pvd = sorted(set(float(x) for x in re.findall(r'timestep="([^"]+)"', open(sys.argv[1]).read())))
t = list(h5py.File(sys.argv[2], 'r')['time'][:])
sys.exit(0 if pvd == t and len(t) == 4 else 1)
PY
then pass vtk-times-are-hdf5-time
else fail vtk-times-are-hdf5-time "$(grep -o 'timestep="[^"]*"' out/vt.pvd | head -4)"; fi
# node numbers: VTK's point k - 1 is flexmbs's node k (point data node_id), at
# the HDF5 file's reference_nodes + displacement of node k; cell k - 1 element k
if problem=$(/usr/bin/python3 - out/vt.h5 out/vt_0003.vtu 2>&1 <<'PY'
import sys, h5py, numpy as np
import xml.etree.ElementTree as ET
f = h5py.File(sys.argv[1], 'r')
body = f['flexible/' + sorted(f['flexible'])[0]]
x_h5 = body['reference_nodes'][:] + body['displacement'][3]            # (nodes, 3)
piece = ET.parse(sys.argv[2]).getroot().find('UnstructuredGrid/Piece')
arrays = {a.get('Name'): a for a in piece.iter('DataArray') if a.get('Name')}
x = np.array(piece.find('Points/DataArray').text.split(), float).reshape(-1, 3)
ids = [int(v) for v in arrays['node_id'].text.split()]
assert ids == list(range(1, len(x) + 1)), ids
assert np.abs(x - x_h5).max() < 1e-12, np.abs(x - x_h5).max()
assert np.abs(body['displacement'][3]).max() > 0, 'no motion to compare'
cells = np.array(arrays['connectivity'].text.split(), int).reshape(-1, 8)
assert (cells + 1 == body['connectivity'][:]).all(), 'connectivity'
elements = [int(v) for v in arrays['element_id'].text.split()]
assert elements == list(range(1, len(cells) + 1)), elements
PY
); then pass vtk-node-ids-are-hdf5-nodes
else fail vtk-node-ids-are-hdf5-nodes "$problem"; fi
# two flexible bodies (inputs/two_soft_links.nml): one piece in the mesh
# file (meshio reads the cells of one piece only), the bodies one after the
# other in the order of field data flexible_names, cell data flexible_id the
# body's number, node_id and element_id numbered in each body; each body's
# points are its reference_nodes + displacement in the HDF5 file's
# /flexible/NAME, its cells its connectivity after the points before it
sed -e "s/t_end   = 0.2 /t_end   = 0.02 /" \
    -e "s#^&output#\&output vtk = 'out/tsl', vtk_format = 'ascii', file = 'out/tsl.h5',#" \
    -e "s/n_output = 21/n_output = 3/" "$root/inputs/two_soft_links.nml" > tsl.nml
expect vtk-two-flexible-run 0 "radau5: NST=" run tsl.nml --quiet
if problem=$(/usr/bin/python3 - out/tsl.h5 out/tsl_0002.vtu 2>&1 <<'PY'
import sys, h5py, numpy as np
import xml.etree.ElementTree as ET
f = h5py.File(sys.argv[1], 'r')
grid = ET.parse(sys.argv[2]).getroot().find('UnstructuredGrid')
codes = [int(c) for c in grid.find('FieldData/DataArray').text.split()]
names = ''.join(chr(c) if c else '\n' for c in codes).split()
assert names == ['upper', 'lower'], names
pieces = grid.findall('Piece')
assert len(pieces) == 1, len(pieces)
piece = pieces[0]
arrays = {a.get('Name'): np.array(a.text.split(), float) for a in piece.iter('DataArray')
          if a.get('Name')}
x = np.array(piece.find('Points/DataArray').text.split(), float).reshape(-1, 3)
cells = arrays['connectivity'].reshape(-1, 8)
points = elements = 0
for k, name in enumerate(names, start=1):
    body = f['flexible/' + name]
    x_h5 = body['reference_nodes'][:] + body['displacement'][2]
    n, ne = len(x_h5), len(body['connectivity'])
    assert np.abs(x[points:points + n] - x_h5).max() < 1e-12, (name, np.abs(x - x_h5).max())
    assert (arrays['node_id'][points:points + n] == np.arange(1, n + 1)).all(), name
    assert (arrays['flexible_id'][elements:elements + ne] == k).all(), name
    assert (arrays['element_id'][elements:elements + ne] == np.arange(1, ne + 1)).all(), name
    assert (cells[elements:elements + ne] == body['connectivity'][:] - 1 + points).all(), name
    points, elements = points + n, elements + ne
assert (points, elements) == (len(x), len(cells)), (points, elements)
assert np.abs(f['flexible/lower/displacement'][2]).max() > 1e-4, 'the lower link did not move'
PY
); then pass vtk-two-flexible-bodies
else fail vtk-two-flexible-bodies "$problem"; fi
# the joints (part 2): the four-bar's four joints and its driver, a point each at
# marker i, by name; the points against the markers computed from the HDF5 file's
# bodies (position + R s), the fixed pivots, the reactions against /joints
sed -e "s/t_end   = 1.0 /t_end   = 0.2 /" \
    -e "s#^&output#\&output vtk = 'out/fbj', vtk_format = 'ascii', file = 'out/fbj.h5',#" \
    -e "s/n_output = 101/n_output = 3/" "$root/inputs/four_bar.nml" > fbj.nml
expect vtk-joints-run 0 "radau5: NST=" run fbj.nml --quiet
if problem=$(/usr/bin/python3 - out/fbj.pvd out/fbj.h5 2>&1 <<'PY'
import sys, re, h5py, numpy as np
import xml.etree.ElementTree as ET
pvd = open(sys.argv[1]).read()
f = h5py.File(sys.argv[2], 'r')
files = re.findall(r'part="2" file="([^"]+)"', pvd)
assert files == ['fbj_joints_%04d.vtu' % k for k in range(3)], files
def arrays(node):
    return {a.get('Name'): a for a in node.iter('DataArray') if a.get('Name')}
def values(a):
    return np.array(a.text.split(), float)
def strings(a):
    codes = [int(c) for c in a.text.split()]
    out, word = [], ''
    for c in codes:
        if c == 0:
            out.append(word)
            word = ''
        else:
            word += chr(c)
    return out
def rotation(body, k):
    return f['bodies/%s/rotation_matrix' % body][k].reshape(3, 3).T   # column by column
names = ['joints/crank pivot', 'joints/crank pin', 'joints/rocker pin', 'joints/rocker pivot',
         'drivers/motor']
for k, name in enumerate(files):
    grid = ET.parse('out/' + name).getroot().find('UnstructuredGrid')
    piece = grid.find('Piece')
    assert piece.get('NumberOfPoints') == '5', piece.attrib
    # field data belongs to the data set: VTK reads none inside a piece
    field = arrays(grid.find('FieldData'))
    assert strings(field['joint_names']) == names, strings(field['joint_names'])
    assert strings(field['joint_types']) == ['revolute', 'spherical', 'universal', 'revolute',
                                            'angle driver'], strings(field['joint_types'])
    x = values(piece.find('Points/DataArray')).reshape(5, 3)
    point = arrays(piece.find('PointData'))
    assert list(values(point['joint_id'])) == [1, 2, 3, 4, 5]
    assert list(values(point['joint_type'])) == [2, 1, 5, 2, 7]
    crank, coupler = f['bodies/crank/position'][k], f['bodies/coupler/position'][k]
    want = np.array([[0, 0, 0],                                          # A on the ground
                     crank + rotation('crank', k) @ [0.05, 0, 0],        # B1 on the crank
                     coupler + rotation('coupler', k) @ [0.2, 0, 0],     # C2 on the coupler
                     [0.35, 0, 0],                                       # D on the ground
                     [0, 0, 0]])                                         # the motor's A
    assert np.abs(x - want).max() < 1e-12, (k, x, want)
    axis = values(point['axis']).reshape(5, 3)
    assert np.abs(axis[2] - rotation('coupler', k) @ [0, 1, 0]).max() < 1e-12, axis[2]
    force = values(point['reaction_force']).reshape(5, 3)
    assert np.abs(force[1] - f['joints/crank pin/reaction_force'][k]).max() < 1e-12
    force_j = values(point['reaction_force_j']).reshape(5, 3)
    assert np.abs(force_j[3] - f['joints/rocker pivot/reaction_force_j'][k]).max() < 1e-12
    assert np.abs(force[1]).max() > 0.1, force                           # not all zero
bodies = ET.parse('out/fbj_bodies_0002.vtu').getroot().find('UnstructuredGrid')
assert strings(arrays(bodies.find('FieldData'))['body_names']) == ['crank', 'coupler', 'rocker']
PY
); then pass vtk-joints-at-markers
else fail vtk-joints-at-markers "$problem"; fi
sed -e "s#^&output#\&output vtk = 'vdp',#" "$root/inputs/van_der_pol.nml" > vdp_vtk.nml
bad vtk-no-bodies "&output: vtk: problem = 'van_der_pol' has no bodies to draw" vdp_vtk.nml

# a rigid body placed off its joints: the initial assembly would move it
# silently; beyond &multibody assembly_tolerance (1 mm) it is bad input
sed -e "s/position = 0.371536305571885, /position = 0.401536305571885, /" \
    -e "s/t_end *= *[0-9.]*/t_end = 0.01/" "$root/inputs/four_bar.nml" > off_joint.nml
bad assembly-moves-body "the initial assembly moves rigid body 'rocker' by" off_joint.nml
expect assembly-names-joint 2 "most violated at the given positions: &joint 'rocker" \
    run off_joint.nml --quiet
sed -e "s/^&multibody/\&multibody assembly_tolerance = 0.1,/" off_joint.nml > off_joint_ok.nml
expect assembly-within-tolerance 0 "initial assembly moved: rigid body 'crank'" \
    run off_joint_ok.nml --quiet
expect assembly-reported 0 "rigid body 'rocker' 3.000000E-02 m" run off_joint_ok.nml --quiet

# inputs that are not regular files are refused at once (a FIFO used to
# block for ever); a mesh declaring more nodes than it holds is refused
# before anything is allocated (2e9 nodes died in an allocation)
mkfifo fifo.nml
check fifo-input 2 "fifo.nml: not a regular file" run fifo.nml --quiet
if [ -n "$problem" ]; then fail fifo-input "$problem"; else pass fifo-input; fi
mkdir -p folder.nml
expect folder-input 2 "folder.nml: is a folder, not a file" run folder.nml --quiet
printf '%s\n' "flexmbs-mesh 1" "nodes 2000000000" "1 0 0 0" > in/huge.mesh
printf '%s\n' "&simulation problem = 'flexible_body', t_end = 0.01 /" \
    "&flexible_body mesh_file = 'in/huge.mesh' /" \
    "&material youngs_modulus = 7e5, density = 920 /" > huge_mesh.nml
bad mesh-count-beyond-file "2000000000 nodes declared, but the file holds only" huge_mesh.nml

# dense matrices beyond the machine's memory: refused before they are
# allocated (they died in an allocation)
printf '%s\n' "&simulation problem = 'flexible_body', t_end = 0.01 /" \
    "&flexible_body lengths = 1, 1, 1, divisions = 30, 30, 30 /" \
    "&material youngs_modulus = 7e5, density = 920 /" \
    "&solver linear_solver = 'dense' /" > dense_big.nml
bad dense-beyond-memory "&solver: linear_solver = 'dense': " dense_big.nml

# Replacing files: a file at an output's path is replaced only when it is
# flexmbs's own result of that kind; anything else needs --force (and is
# left as it was without); two outputs of one run are never one file
py=/usr/bin/python3
[ -x "$py" ] || py=python3
printf '%s\n&solver rtol = 1e-4, atol = 1e-4, h0 = 1e-6 /\n%s\n' "$sim" \
    "&output file = 'out/keep.h5', table = 'out/keep.md' /" > replace.nml
echo "precious notes" > out/keep.h5
untouched foreign-output-refused \
    "replace.nml: &output: file: 'out/keep.h5' exists and is not an HDF5 file: refused; --force replaces it" \
    out/keep.h5 run replace.nml --quiet
"$py" -c "import h5py; h5py.File('out/keep.h5', 'w')['x'] = [1.0]" 2>&1
untouched foreign-hdf5-refused "'out/keep.h5' exists and is an HDF5 file not written by flexmbs" \
    out/keep.h5 run replace.nml --quiet
expect foreign-output-forced 0 "radau5: NST=" run replace.nml --quiet --force
expect flexmbs-result-replaced 0 "radau5: NST=" run replace.nml --quiet
echo "| my | own | table |" > out/keep.md
untouched foreign-table-refused "&output: table: 'out/keep.md' exists and is not a table written by flexmbs" \
    out/keep.md run replace.nml --quiet
rm -f out/keep.md
printf '%s\n&output file = %s, table = %s /\n' "$sim" "'out/same.md'" "'./out/../out/same.md'" \
    > same.nml
bad two-outputs-one-file "&output: file: 'out/same.md' and &output: table: './out/../out/same.md' are the same file" \
    same.nml
sed -e "s#file = 'none'#file = 'out/vis_0001.vtu'#" vis.nml > vis_same.nml
rm -f out/vis_0001.vtu
bad hdf5-is-a-vtk-piece "&output: file: 'out/vis_0001.vtu' and &output: vtk: 'out/vis_0001.vtu' are the same file" \
    vis_same.nml
expect vtk-rerun 0 "radau5: NST=" run vis.nml --quiet
echo "<VTKFile/>" > out/vis_0001.vtu
untouched vtk-foreign-piece "&output: vtk: 'out/vis_0001.vtu' exists and is not a ParaView file written by flexmbs" \
    out/vis_0001.vtu run vis.nml --quiet
rm -f out/vis_0001.vtu
echo "<VTKFile/>" > out/vis_joints_0001.vtu
untouched vtk-foreign-joints-piece "&output: vtk: 'out/vis_joints_0001.vtu' exists and is not a ParaView file written by flexmbs" \
    out/vis_joints_0001.vtu run vis.nml --quiet
# the XDMF file beside an HDF5 result with a flexible body is an output as
# well: a foreign file there is refused and kept, --force replaces it, a
# later run its own; one that would be the scene file is refused
sed -e "s#file = 'none'#file = 'out/vx.h5'#" vis.nml > vx.nml
echo "<Xdmf/>" > out/vx.xdmf
untouched xdmf-foreign "&output: file (its XDMF file): 'out/vx.xdmf' exists and is not an XDMF file written by flexmbs" \
    out/vx.xdmf run vx.nml --quiet
expect xdmf-forced 0 "for ParaView (XDMF): out/vx.xdmf" run vx.nml --quiet --force
expect xdmf-replaced 0 "for ParaView (XDMF): out/vx.xdmf" run vx.nml --quiet
sed -e "s#file = 'none'#file = 'self.h5'#" vis.nml > self.xdmf
untouched xdmf-is-the-scene "&output: file (its XDMF file): 'self.xdmf' is the scene file itself" \
    self.xdmf run self.xdmf --quiet
echo "notes" > study_reference.h5
untouched study-reference-foreign "&study: reference_file: 'study_reference.h5' exists and is not an HDF5 file" \
    study_reference.h5 reference study.nml --quiet
expect study-reference-forced 0 "written: study_reference.h5" reference study.nml --quiet --force
# (a table's name ends in .md, .csv or .tex; a reference's may too)
sed -e "s#^ *pmax.*#&, reference_file = 'ref.md', table = './ref.md'#" \
    -e "s/tolerances .*/tolerances = 1e-3/" -e "s/check_solver .*/check_solver = 'none'/" \
    study.nml > table_is_reference.nml
"$exe" reference table_is_reference.nml --quiet > /dev/null 2>&1
untouched study-table-is-reference "&study: table: './ref.md' is an input of the sweep (the reference file)" \
    ref.md sweep table_is_reference.nml --quiet

# an output grid whose HDF5 file cannot fit on its file system: refused
# before the run (n_output = 1e8 on the five-body ran for hours)
sed -e "s/n_output *= *[0-9]*/n_output = 1000000000/" "$root/inputs/five_body.nml" > many_outputs.nml
bad output-beyond-disk "&output: n_output = 1000000000: the HDF5 file 'many_outputs.h5' would need ~" \
    many_outputs.nml
# one that fits but holds gigabytes is announced before the run, size and
# time (the fine five-body: ~12 000 values a record, 3.7 GB at least); the
# run is stopped once it has said so
sed -e "s/n_output *= *[0-9]*/n_output = 40000/" -e "s#^&output#\&output file = 'out/big.h5',#" \
    -e "s#mesh_file = '\([^/']\)#mesh_file = '$root/inputs/\1#" "$root/inputs/five_body_fine.nml" \
    > big_output.nml
"$exe" run big_output.nml --quiet > /dev/null 2> big_output.err &
big=$!
for _ in $(seq 150); do
    grep -q "will hold at least" big_output.err 2>/dev/null && break
    kill -0 "$big" 2>/dev/null || break
    sleep 0.1
done
kill -KILL "$big" 2>/dev/null; wait "$big" 2>/dev/null
if grep -qE "big_output.nml: &output: n_output = 40000: the HDF5 file '.*out/big.h5' will hold at least [0-9.]+ GB; writing it alone takes about [0-9]+ s" big_output.err
then pass large-output-announced
else fail large-output-announced "standard error: $(head -c 400 big_output.err)"; fi
rm -f out/big.h5

# issue 16's remaining defects, each as the user met it:
# an output grid beyond memory died in an allocation
sed -e "s/n_output *= *[0-9]*/n_output = 2147483647/" "$root/inputs/van_der_pol.nml" > n_huge.nml
bad n-output-beyond-memory "&output: n_output = 2147483647: 2.147484E+09 output times need ~17.2 GB" \
    n_huge.nml
# a marker whose x axis is its z axis ran
sed -e "s/&marker name = 'A1', body = 'crank',   position = -0.05, 0.0, 0.0 \//\&marker name = 'A1', body = 'crank', position = -0.05, 0.0, 0.0, z_axis = 0, 0, 1, x_axis = 0, 0, 2 \//" \
    "$root/inputs/four_bar.nml" > parallel_axes.nml
bad marker-axes-parallel "&marker: x_axis = 0, 0, 2: must not be parallel to z_axis" parallel_axes.nml
# inputs of 3 GiB and 4.5 GiB (sparse files): 'cannot determine its size' and
# a 4.5 GiB file read as 512 MiB before sizes were counted in 64 bits
truncate -s 3G big3.nml && truncate -s 4500M big45.nml
expect input-3-gib 2 "big3.nml: 3.2 GB, larger than an input can be (2 GiB)" run big3.nml --quiet
expect input-4-5-gib 2 "big45.nml: 4.7 GB, larger than an input can be (2 GiB)" run big45.nml --quiet
rm -f big3.nml big45.nml
# a mesh file relative to the scene's folder, run from elsewhere (it was
# resolved against the working directory)
mkdir -p scenes/m
cp "$root/inputs/meshes/bar_hex8.mesh" scenes/m/bar.mesh
printf '%s\n' "&simulation problem = 'flexible_body', t_end = 1e-3 /" \
    "&flexible_body mesh_file = 'bar.mesh', fixed = 'clamp' /" \
    "&material youngs_modulus = 7e5, density = 920 /" \
    "&output file = 'r.h5', n_output = 2 /" > scenes/m/bar.nml
expect mesh-relative-to-scene 0 "radau5: NST=" run scenes/m/bar.nml --quiet
if [ -s scenes/m/r.h5 ]; then pass output-relative-to-scene
else fail output-relative-to-scene "scenes/m/r.h5 was not written: $(ls scenes/m)"; fi

# flexmbs modes (docs/modes.md): the eigen-analysis of a scene on standard
# output with nothing on standard error, the spectrum table, the plot when
# gnuplot is there and a note when it is not; bad options exit 2
expect help-modes 0 "flexmbs modes FILE.nml" --help
mkdir -p m
# spectrum_problems CSV OUT: what is wrong with the spectrum file CSV (rows
# mode, Re, Im, |lambda|, omega, f, zeta, angle) against its definitions:
# |lambda| = hypot(Re, Im), omega = |Im|, f = omega / 2 pi, zeta =
# -Re / |lambda|, angle = acos(zeta) in degrees (to 1e-12, the angle 1e-9);
# modes numbered 0 (zero eigenvalues), then 1, 2, ... by rising |lambda|,
# each a real eigenvalue or a conjugate pair; the modes 1 to 5 of the table
# in OUT are the CSV's (Re and Im to the table's 11 digits). Empty when
# nothing.
spectrum_problems() {
    awk -F, -v table="$2" '
        function abs(x) { return x < 0 ? -x : x }
        function off(a, b, tol) { return abs(a - b) > tol * (abs(b) > 1 ? abs(b) : 1) }
        function say(text) { if (problem == "") problem = FILENAME " row " n ": " text }
        BEGIN {
            pi = atan2(0, -1)
            while ((getline line < table) > 0)
                if (line ~ /^ +[1-5] +-?[0-9]/) {
                    split(line, w, " ")
                    tre[w[1] + 0] = w[2] + 0; tim[w[1] + 0] = w[3] + 0
                }
        }
        /^#/ { next }
        {
            n++
            mode = $1 + 0; re = $2 + 0; im = $3 + 0; modulus = $4 + 0
            if (off(modulus, sqrt(re * re + im * im), 1e-12)) say("|lambda| is not hypot(Re, Im)")
            if (off($5 + 0, abs(im), 1e-12)) say("omega is not |Im|")
            if (off($6 + 0, abs(im) / (2 * pi), 1e-12)) say("f is not omega / 2 pi")
            if (modulus > 0 && off($7 + 0, -re / modulus, 1e-12)) say("zeta is not -Re/|lambda|")
            z = $7 + 0
            if (modulus > 0 && off($8 + 0, atan2(sqrt(1 - z * z), z) * 180 / pi, 1e-9))
                say("angle is not acos(zeta)")
            if (mode == last && mode > 0) {
                if (++rows > 2 || off(re, last_re, 1e-12) || off(im, -last_im, 1e-12))
                    say("mode " mode ": not a conjugate pair")
            } else {
                if (mode < last || (mode > 0 && mode != last + 1)) say("mode " mode " after " last)
                if (mode > 1 && modulus < last_modulus * (1 - 1e-12)) say("|lambda| falls")
                rows = 1
            }
            if (mode in tre && (off(re, tre[mode], 1e-9) || off(abs(im), abs(tim[mode]), 1e-9)))
                say("mode " mode " differs from the table")
            if (mode in tre) seen[mode] = 1
            last = mode; last_re = re; last_im = im; last_modulus = modulus
        }
        END {
            for (m = 1; m <= 5; m++) if (!(m in seen)) say("table mode " m " missing")
            print problem
        }' "$1"
}

# modes_run NAME ARGS...: exit 0, empty standard error; output in m/NAME.out
modes_run() {
    local name=$1
    shift
    "$exe" modes "$@" > "m/$name.out" 2> "m/$name.err"
    local rc=$?
    problem=""
    if [ "$rc" -ne 0 ]; then problem="exit $rc: $(head -c 400 "m/$name.err")"
    elif [ -s "m/$name.err" ]; then problem="standard error: $(head -c 400 "m/$name.err")"
    fi
}
modes_run five_body "$root/inputs/five_body.nml" --count 5 --output m/five_body
if [ -z "$problem" ]; then
    out=$(cat m/five_body.out)
    rows=$(grep -cE '^ +[1-5] +-?[0-9]\.[0-9]{10}E[+-][0-9]{2} +-?[0-9]\.[0-9]{10}E[+-][0-9]{2} +[0-9]\.[0-9]{6}E[+-][0-9]{2} +[0-9]\.[0-9]{6}E[+-][0-9]{2} +-?[0-9]+\.[0-9]{4} +[0-9]+\.[0-9]{4}$' <<<"$out")
    for line in "^modes of 'five-body mechanism \(damped\)' \(.*/inputs/five_body.nml\) at t = 0.000000E\+00 s$" \
        "^linearised: formulation 'ggl' as ddassl integrates it, n = 547 unknowns; dense QZ" \
        "^eigenvalues: 266 finite, 281 infinite" "^expected finite: 266 = 2 x 131 " \
        "^  mode   Re\(lambda\) \[1/s\]   Im\(lambda\) \[1/s\]  omega \[rad/s\]      f \[Hz\]     zeta  angle \[deg\]$" \
        "^ddassl on the same scene \(rtol 1.000000E-06, atol 1.000000E-06, p_max 5\): NST=" \
        "^accepted steps: [0-9]+, h from " "^  BDF-5      51.8398 " "^spectrum: m/five_body.csv$" \
        "^plot: "; do
        grep -qE -- "$line" <<<"$out" || { problem="no line '$line' in: $out"; break; }
    done
    [ -z "$problem" ] && [ "$rows" -ne 5 ] && problem="$rows mode rows, not 5: $out"
    [ -z "$problem" ] && [ "$(head -1 m/five_body.csv)" != "# written by flexmbs $("$exe" --version | cut -d' ' -f2)" ] &&
        problem="m/five_body.csv: first line $(head -1 m/five_body.csv)"
    [ -z "$problem" ] && [ "$(grep -vc '^#' m/five_body.csv)" -ne 266 ] &&
        problem="m/five_body.csv: $(grep -vc '^#' m/five_body.csv) rows, not 266"
    [ -z "$problem" ] && problem=$(spectrum_problems m/five_body.csv m/five_body.out)
fi
if [ -n "$problem" ]; then fail modes-five-body "$problem"; else pass modes-five-body; fi
# the plot needs gnuplot; without it the test says SKIP (counted neither way)
if ! command -v gnuplot > /dev/null; then
    echo "SKIP cli/modes-five-body-plot: gnuplot is not on PATH, m/five_body.png not checked"
elif ! grep -q '^plot: m/five_body.png$' m/five_body.out; then
    fail modes-five-body-plot "no plot: $(cat m/five_body.out)"
elif [ "$(head -c 4 m/five_body.png | tail -c 3)" != "PNG" ]; then
    fail modes-five-body-plot "m/five_body.png is not a PNG"
else
    pass modes-five-body-plot
fi
# the driven four-bar has no degree of freedom: 3 finite eigenvalues (its
# quaternions' lengths), the rest infinite
modes_run four_bar "$root/inputs/four_bar.nml" --output m/four_bar --no-run
if [ -z "$problem" ] && ! grep -q '^eigenvalues: 3 finite, 72 infinite' m/four_bar.out; then
    problem="$(cat m/four_bar.out)"
fi
if [ -n "$problem" ]; then fail modes-four-bar "$problem"; else pass modes-four-bar; fi
# no gnuplot on PATH: said, no PNG, exit 0
PATH=/nonexistent "$exe" modes "$root/inputs/five_body.nml" --output m/five_body --no-run \
    > m/no_gnuplot.out 2> m/no_gnuplot.err
rc=$?
if [ "$rc" -ne 0 ] || [ -s m/no_gnuplot.err ] ||
    ! grep -q '^plot: skipped (gnuplot not found on PATH' m/no_gnuplot.out || [ -e m/five_body.png ]; then
    fail modes-without-gnuplot "exit $rc, $(cat m/no_gnuplot.err m/no_gnuplot.out | tail -3)"
else
    pass modes-without-gnuplot
fi
# ARPACK: the five lowest modes as the dense QZ has them
modes_run arpack "$root/inputs/five_body.nml" --output m/arpack --no-run --method arpack --count 5
if [ -z "$problem" ]; then
    grep -q 'ARPACK shift-invert around sigma = -1.000000E+00' m/arpack.out ||
        problem="$(cat m/arpack.out)"
    lowest() { grep -E '^ +[1-5] ' "$1" | awk '{ printf "%d %.6e %.6e\n", $1, $2, $3 }'; }
    [ -z "$problem" ] && [ "$(lowest m/arpack.out)" != "$(lowest m/five_body.out)" ] &&
        problem="ARPACK's modes differ from QZ's: $(grep -E '^ +[1-5] ' m/arpack.out)"
fi
if [ -n "$problem" ]; then fail modes-arpack "$problem"; else pass modes-arpack; fi
expect modes-time-outside 2 "five_body.nml: --time 2.000000E+00: outside the scene's [t_start, t_end]" \
    modes "$root/inputs/five_body.nml" --time 2 --output m/x
expect modes-count-word 2 "--count ten: needs a whole number >= 1" \
    modes "$root/inputs/five_body.nml" --count ten
expect modes-method 2 "--method qz: use auto, dense or arpack" \
    modes "$root/inputs/five_body.nml" --method qz
expect modes-no-scene 2 "modes needs a scene file" modes --count 3
echo "my picture" > m/foreign.png
untouched modes-foreign-png "modes: plot: 'm/foreign.png' exists and is not a plot written by flexmbs" \
    m/foreign.png modes "$root/inputs/four_bar.nml" --output m/foreign --no-run

echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
