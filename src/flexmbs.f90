!> The umbrella module: `use flexmbs` gives the public API.
module flexmbs
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_ok, status_bad_input, &
        status_solver_failure, status_io_error, status_interrupted, reason_name
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, &
        storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_band, only: band_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: rejections_t, cause_error_test, cause_newton_diverged, &
        cause_newton_slow, cause_singular_matrix, cause_model_refused, cause_projection, &
        cause_unstable, cause_count, cause_keys, cause_labels
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t, radau5_dense_t, radau5_native_t
    use flexmbs_dae_ida, only: ida_t, ida_native_t
    use flexmbs_dae_residual_problem, only: residual_problem_t, dae_residual_t
    use flexmbs_dae_ddassl, only: ddassl_t, ddassl_dense_t, ddassl_native_t
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_dae_bdf_stability, only: bdf_stability_angle, bdf_boundary_locus
    use flexmbs_fe_hexahedron, only: hexahedron_t, new_hexahedron, hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t, node_set_t, element_set_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_mesh_file, only: read_mesh, write_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_fe_statics, only: solve_static, static_options_t, static_report_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index1, &
        formulation_index2, formulation_index3, formulation_ggl, block_q, block_v, block_a, &
        block_lambda, block_mu
    use flexmbs_mbs_rigid_body, only: rigid_bodies_t, rigid_body_t, new_rigid_bodies, &
        rigid_body_energy, rigid_body_momenta
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        constraint_derivatives_analytic, constraint_derivatives_ad, driver_t, driver_values, &
        node_frame_t, part_rigid, part_chain, part_flexible, part_modal, part_frame
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_marker_t, chain_joint_revolute, chain_joint_prismatic
    use flexmbs_problems_mechanisms, only: new_mechanism, mechanism_slider_crank, &
        mechanism_four_bar
    use flexmbs_problems_pendulum, only: pendulum_mechanical_t, new_pendulum_mechanical, &
        pendulum_mechanical_initial, pendulum_angle_exact
    use flexmbs_io_vtk_sink, only: vtk_sink_t
    use flexmbs_mbs_flexible_marker, only: flexible_marker_t, new_flexible_marker
    use flexmbs_mbs_joint, only: joint_spherical, joint_revolute, joint_cylindrical, &
        joint_prismatic, joint_universal, joint_fixed, joint_planar
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_io_namelist, only: scene_input_t, read_scene, parse_scene, scene_dae_options
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_table, only: stats_row_t, new_stats_row, table_text, write_table, &
        table_markdown, table_csv, table_latex
    use flexmbs_io_progress, only: progress_t, new_progress
    use flexmbs_io_multi_sink, only: multi_sink_t
    use flexmbs_run_runner, only: run_scene, run_result_t
    use flexmbs_run_plan, only: run_plan_t, make_plan
    use flexmbs_run_problem_factory, only: build_problem
    use flexmbs_run_solver_factory, only: build_solver, new_solver
    use flexmbs_run_catalogue, only: solver_info_t, problem_info_t, &
        solver_info, problem_info
    implicit none
    public
end module flexmbs
