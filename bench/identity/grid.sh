#!/usr/bin/env bash
# Behaviour unchanged? Every scene of inputs/ cut short, with each solver, and
# variants (every step to the sink; finite-difference Jacobians, dense and
# KLU, tight, loose and capped runs, MEXAX's Euler base, ...): 272 runs, a
# few minutes on one core.
#
#   bash bench/identity/grid.sh FLEXMBS OUTDIR     (EXTRA="key = value" adds
#                                                   a setting to every &solver)
#
# Run it with the executable before a change and after it, then compare the
# two folders: python3 bench/compare_results.py BEFORE AFTER [--ignore-input]
# (every HDF5 dataset and attribute but timings; --ignore-input when EXTRA
# made the scene texts differ). E.g. the condensed Newton systems against
# the behaviour before them: EXTRA="newton_system = 'full'" after.
set -u
bin=$(readlink -f "$1"); out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
gen=$root/bench/identity/scene_variant.py
mkdir -p "$out"; cd "$out" || exit 1
rm -rf meshes; cp -r $root/inputs/meshes .
export OPENBLAS_NUM_THREADS=1
run() {  # NAME SCENE T_END SOLVER [k=v ...]
    local name=$1 scene=$2 tend=$3 solver=$4; shift 4
    python3 $gen $root/inputs/$scene.nml $name.nml $name $tend $solver "$@"
    [ -n "${EXTRA:-}" ] && sed -i "/^\&solver/s/^\&solver/\&solver $EXTRA,/" $name.nml
    "$bin" run $name.nml --quiet > $name.out 2> $name.err
    echo $? > $name.rc
}
small="arm_with_pad bushing_mount double_pendulum_chain face_hinge flexible_cantilever four_bar four_bar_chain four_bar_chains pendulum rigid_flexible_pendulum two_soft_links"
solvers="radau5 ddassl ida mexax"
# A: default settings
for s in $solvers; do
    for n in $small; do run A_${n}_$s $n 0.1 $s; done
    run A_van_der_pol_$s van_der_pol 0.5 $s
    for n in five_body five_body_undamped; do run A_${n}_$s $n 0.05 $s; done
    # scenes added later, default settings only: modal bodies, the planar joint
    run A_five_body_modal_$s five_body_modal 0.05 $s
    run A_planar_slider_$s planar_slider 0.1 $s
    for n in five_body_fine five_body_fine_undamped; do
        if [ $s = mexax ]; then run A_${n}_$s $n 0.003 $s max_steps=25
        else run A_${n}_$s $n 0.003 $s; fi
    done
done
# B: every accepted step to the sink
for s in $solvers; do
    for n in $small van_der_pol five_body five_body_undamped; do
        run B_${n}_$s $n 0.02 $s every_step=.true.
    done
done
# C: variants on a few scenes
for n in pendulum four_bar van_der_pol five_body bushing_mount face_hinge; do
    tend=0.05
    run C_${n}_radau5_fd $n $tend radau5 "jacobian='fd'"
    run C_${n}_radau5_classical $n $tend radau5 "controller='classical'" zero_start=.true.
    run C_${n}_radau5_nit2 $n $tend radau5 nit=2 thet=-1.0
    run C_${n}_radau5_dense $n $tend radau5 "linear_solver='dense'"
    run C_${n}_radau5_klu $n $tend radau5 "linear_solver='klu'"
    run C_${n}_ida_dense $n $tend ida "linear_solver='dense'"
    run C_${n}_ida_klu $n $tend ida "linear_solver='klu'"
    run C_${n}_ida_fd $n $tend ida "jacobian='fd'"
    run C_${n}_ddassl_fd $n $tend ddassl "jacobian='fd'" initial_derivative=.true.
    run C_${n}_mexax_euler $n $tend mexax "mexax_base='euler'" max_extrapolation=4
    run C_${n}_mexax_dense $n $tend mexax "linear_solver='dense'"
    run C_${n}_mexax_klu $n $tend mexax "linear_solver='klu'"
    for s in $solvers; do
        run C_${n}_${s}_tight $n 0.02 $s rtol=1.0e-10 atol=1.0e-10
        run C_${n}_${s}_loose $n $tend $s rtol=1.0e-2 atol=1.0e-2 h0=1.0e-3 hmax=4.0e-3
        run C_${n}_${s}_maxsteps $n $tend $s max_steps=5 every_step=.true.
    done
done
ls *.rc | wc -l
