!> The one test driver: runs every suite and prints `N passed, M failed`.
!> An optional argument filters tests by substring of 'suite/test'.
program flexmbs_tests
    use testing, only: run_suite
    use test_linalg, only: collect_linalg
    use test_klu, only: collect_klu
    use test_mumps, only: collect_mumps
    use test_band, only: collect_band
    use test_problems, only: collect_problems
    use test_radau5, only: collect_radau5
    use test_radau5_dae, only: collect_radau5_dae
    use test_radau5_sparse, only: collect_radau5_sparse
    use test_io, only: collect_io
    use test_scene_input, only: collect_scene_input
    use test_bdf_stability, only: collect_bdf_stability
    use test_reference, only: collect_reference
    use test_ida, only: collect_ida
    use test_ddassl, only: collect_ddassl
    use test_mexax, only: collect_mexax
    use test_mexax_sparse, only: collect_mexax_sparse
    use test_mexax_accuracy, only: collect_mexax_accuracy
    use test_mexax_deuflhard, only: collect_mexax_deuflhard
    use test_fe, only: collect_fe
    use test_fe_element, only: collect_fe_element
    use test_fe_body, only: collect_fe_body
    use test_fe_dynamics, only: collect_fe_dynamics
    use test_fe_statics, only: collect_fe_statics
    use test_fe_mesh, only: collect_fe_mesh
    use test_fe_detf, only: collect_fe_detf
    use test_fe_assembly, only: collect_fe_assembly
    use test_rotation, only: collect_rotation
    use test_dual, only: collect_dual
    use test_constraint_primitives, only: collect_constraint_primitives
    use test_formulation, only: collect_formulation
    use test_rigid_body, only: collect_rigid_body
    use test_mbs_system, only: collect_mbs_system
    use test_joint_types, only: collect_joint_types
    use test_planar_joint, only: collect_planar_joint
    use test_force_elements, only: collect_force_elements
    use test_bushing_mount, only: collect_bushing_mount
    use test_mechanisms, only: collect_mechanisms
    use test_rigid_chain, only: collect_rigid_chain
    use test_chain_derivatives, only: collect_chain_derivatives
    use test_flexible_marker, only: collect_flexible_marker
    use test_multibody_scene, only: collect_multibody_scene
    use test_flexible_coupling, only: collect_flexible_coupling
    use test_two_flexible, only: collect_two_flexible
    use test_set_markers, only: collect_set_markers
    use test_arm_with_pad, only: collect_arm_with_pad
    use test_node_frame, only: collect_node_frame
    use test_study, only: collect_study
    use test_run, only: collect_run
    use test_restart, only: collect_restart
    use test_rejections, only: collect_rejections
    use test_chain_coupling, only: collect_chain_coupling
    use test_sparse_formulation, only: collect_sparse_formulation
    use test_condensed_newton, only: collect_condensed_newton
    use test_structured_saddle, only: collect_structured_saddle
    use test_out_of_memory, only: collect_out_of_memory
    use test_modes, only: collect_modes
    use test_modal_basis, only: collect_modal_basis
    use test_modal_body, only: collect_modal_body
    use test_modal_frame, only: collect_modal_frame
    use test_modal_system, only: collect_modal_system
    use test_modal_scene, only: collect_modal_scene
    implicit none
    integer :: npassed, nfailed, nargs
    character(len=256) :: filter

    filter = ''
    nargs = command_argument_count()
    if (nargs >= 1) call get_command_argument(1, filter)
    npassed = 0
    nfailed = 0
    call run_suite('linalg', collect_linalg(), filter, npassed, nfailed)
    call run_suite('klu', collect_klu(), filter, npassed, nfailed)
    call run_suite('mumps', collect_mumps(), filter, npassed, nfailed)
    call run_suite('band', collect_band(), filter, npassed, nfailed)
    call run_suite('problems', collect_problems(), filter, npassed, nfailed)
    call run_suite('radau5', collect_radau5(), filter, npassed, nfailed)
    call run_suite('radau5_dae', collect_radau5_dae(), filter, npassed, nfailed)
    call run_suite('radau5_sparse', collect_radau5_sparse(), filter, npassed, nfailed)
    call run_suite('io', collect_io(), filter, npassed, nfailed)
    call run_suite('scene_input', collect_scene_input(), filter, npassed, nfailed)
    call run_suite('bdf_stability', collect_bdf_stability(), filter, npassed, nfailed)
    call run_suite('reference', collect_reference(), filter, npassed, nfailed)
    call run_suite('ida', collect_ida(), filter, npassed, nfailed)
    call run_suite('ddassl', collect_ddassl(), filter, npassed, nfailed)
    call run_suite('mexax', collect_mexax(), filter, npassed, nfailed)
    call run_suite('mexax_sparse', collect_mexax_sparse(), filter, npassed, nfailed)
    call run_suite('mexax_accuracy', collect_mexax_accuracy(), filter, npassed, nfailed)
    call run_suite('mexax_deuflhard', collect_mexax_deuflhard(), filter, npassed, nfailed)
    call run_suite('fe', collect_fe(), filter, npassed, nfailed)
    call run_suite('fe_element', collect_fe_element(), filter, npassed, nfailed)
    call run_suite('fe_body', collect_fe_body(), filter, npassed, nfailed)
    call run_suite('fe_dynamics', collect_fe_dynamics(), filter, npassed, nfailed)
    call run_suite('fe_statics', collect_fe_statics(), filter, npassed, nfailed)
    call run_suite('fe_mesh', collect_fe_mesh(), filter, npassed, nfailed)
    call run_suite('fe_detf', collect_fe_detf(), filter, npassed, nfailed)
    call run_suite('fe_assembly', collect_fe_assembly(), filter, npassed, nfailed)
    call run_suite('rotation', collect_rotation(), filter, npassed, nfailed)
    call run_suite('dual', collect_dual(), filter, npassed, nfailed)
    call run_suite('constraint_primitives', collect_constraint_primitives(), filter, &
                   npassed, nfailed)
    call run_suite('formulation', collect_formulation(), filter, npassed, nfailed)
    call run_suite('rigid_body', collect_rigid_body(), filter, npassed, nfailed)
    call run_suite('mbs_system', collect_mbs_system(), filter, npassed, nfailed)
    call run_suite('joint_types', collect_joint_types(), filter, npassed, nfailed)
    call run_suite('planar_joint', collect_planar_joint(), filter, npassed, nfailed)
    call run_suite('force_elements', collect_force_elements(), filter, npassed, nfailed)
    call run_suite('bushing_mount', collect_bushing_mount(), filter, npassed, nfailed)
    call run_suite('mechanisms', collect_mechanisms(), filter, npassed, nfailed)
    call run_suite('rigid_chain', collect_rigid_chain(), filter, npassed, nfailed)
    call run_suite('chain_derivatives', collect_chain_derivatives(), filter, npassed, &
                   nfailed)
    call run_suite('flexible_marker', collect_flexible_marker(), filter, npassed, nfailed)
    call run_suite('multibody_scene', collect_multibody_scene(), filter, npassed, nfailed)
    call run_suite('flexible_coupling', collect_flexible_coupling(), filter, npassed, &
                   nfailed)
    call run_suite('two_flexible', collect_two_flexible(), filter, npassed, nfailed)
    call run_suite('set_markers', collect_set_markers(), filter, npassed, nfailed)
    call run_suite('arm_with_pad', collect_arm_with_pad(), filter, npassed, nfailed)
    call run_suite('chain_coupling', collect_chain_coupling(), filter, npassed, nfailed)
    call run_suite('sparse_formulation', collect_sparse_formulation(), filter, npassed, &
                   nfailed)
    call run_suite('condensed_newton', collect_condensed_newton(), filter, npassed, nfailed)
    call run_suite('structured_saddle', collect_structured_saddle(), filter, npassed, nfailed)
    call run_suite('out_of_memory', collect_out_of_memory(), filter, npassed, nfailed)
    call run_suite('modes', collect_modes(), filter, npassed, nfailed)
    call run_suite('modal_basis', collect_modal_basis(), filter, npassed, nfailed)
    call run_suite('modal_body', collect_modal_body(), filter, npassed, nfailed)
    call run_suite('modal_frame', collect_modal_frame(), filter, npassed, nfailed)
    call run_suite('modal_system', collect_modal_system(), filter, npassed, nfailed)
    call run_suite('modal_scene', collect_modal_scene(), filter, npassed, nfailed)
    call run_suite('node_frame', collect_node_frame(), filter, npassed, nfailed)
    call run_suite('study', collect_study(), filter, npassed, nfailed)
    call run_suite('run', collect_run(), filter, npassed, nfailed)
    call run_suite('restart', collect_restart(), filter, npassed, nfailed)
    call run_suite('rejections', collect_rejections(), filter, npassed, nfailed)
    write (*, '(i0,a,i0,a)') npassed, ' passed, ', nfailed, ' failed'
    if (nfailed > 0) error stop 1
end program flexmbs_tests
