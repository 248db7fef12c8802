//! The unit tests of `coulomb` (modules `#[cfg(feature = "unit-tests")] pub mod tests`
//! of its library), each run by a `#[test]` at its module's path: compiled once, with the
//! library, instead of in a second build of the whole crate as a test harness
//! (docs/testing.md). Written by `scripts/unit_tests.py`; do not edit.

mod atomic {
    mod tests {
        use coulomb::unit_tests::atomic::tests as t;
        #[test]
        fn stale_temporaries_of_dead_processes_are_removed() {
            t::stale_temporaries_of_dead_processes_are_removed()
        }
        #[test]
        fn atomic_write_replaces_and_leaves_no_temporary() {
            t::atomic_write_replaces_and_leaves_no_temporary()
        }
        #[test]
        fn fifos_and_dangling_links_are_refused_and_left_as_they_are() {
            t::fifos_and_dangling_links_are_refused_and_left_as_they_are()
        }
        #[test]
        fn a_link_to_a_regular_file_is_kept_and_its_target_replaced() {
            t::a_link_to_a_regular_file_is_kept_and_its_target_replaced()
        }
        #[test]
        fn a_device_node_is_refused_and_stays_a_device() {
            t::a_device_node_is_refused_and_stays_a_device()
        }
        #[test]
        fn a_socket_is_refused() {
            t::a_socket_is_refused()
        }
    }
}
mod barrier {
    mod tests {
        use coulomb::unit_tests::barrier::tests as t;
        #[test]
        fn nt_scaling_maps_b_and_a_to_the_same_point() {
            t::nt_scaling_maps_b_and_a_to_the_same_point()
        }
        #[test]
        fn solves_rank_deficient_problems_and_reports_the_stored_error() {
            t::solves_rank_deficient_problems_and_reports_the_stored_error()
        }
        #[test]
        fn a_run_jammed_near_the_end_of_its_path_stops_for_the_end_game() {
            t::a_run_jammed_near_the_end_of_its_path_stops_for_the_end_game()
        }
        #[test]
        fn the_skeleton_gives_the_steps_of_the_sparse_lu() {
            t::the_skeleton_gives_the_steps_of_the_sparse_lu()
        }
        #[test]
        fn a_run_gives_up_the_skeleton_after_its_strikes() {
            t::a_run_gives_up_the_skeleton_after_its_strikes()
        }
        #[test]
        fn the_schur_complement_gives_the_steps_of_the_sparse_lu() {
            t::the_schur_complement_gives_the_steps_of_the_sparse_lu()
        }
        #[test]
        fn solves_two_dimensional_problems() {
            t::solves_two_dimensional_problems()
        }
        #[test]
        fn a_frictionless_contact_or_an_empty_problem_takes_no_step() {
            t::a_frictionless_contact_or_an_empty_problem_takes_no_step()
        }
        #[test]
        fn max_step_stops_at_the_boundary() {
            t::max_step_stops_at_the_boundary()
        }
    }
}
mod cone {
    mod tests {
        use coulomb::unit_tests::cone::tests as t;
        #[test]
        fn known_projections() {
            t::known_projections()
        }
        #[test]
        fn projection_is_idempotent_and_in_cone() {
            t::projection_is_idempotent_and_in_cone()
        }
        #[test]
        fn projection_is_nonexpansive() {
            t::projection_is_nonexpansive()
        }
        #[test]
        fn moreau_decomposition() {
            t::moreau_decomposition()
        }
    }
}
mod deadline {
    mod tests {
        use coulomb::unit_tests::deadline::tests as t;
        #[test]
        fn huge_limits_mean_no_deadline_and_never_panic() {
            t::huge_limits_mean_no_deadline_and_never_panic()
        }
        #[test]
        fn a_cancelled_deadline_has_passed() {
            t::a_cancelled_deadline_has_passed()
        }
    }
}
mod delassus {
    mod tests {
        use coulomb::unit_tests::delassus::tests as t;
        #[test]
        fn block_diagonal_mass_matches_dense() {
            t::block_diagonal_mass_matches_dense()
        }
        #[test]
        fn large_coupled_mass_matches_dense() {
            t::large_coupled_mass_matches_dense()
        }
        #[test]
        fn slightly_asymmetric_ill_conditioned_mass_is_solved_exactly() {
            t::slightly_asymmetric_ill_conditioned_mass_is_solved_exactly()
        }
        #[test]
        fn symmetrize_in_place_equals_the_half_sum() {
            t::symmetrize_in_place_equals_the_half_sum()
        }
    }
}
mod equality {
    mod tests {
        use coulomb::unit_tests::equality::tests as t;
        #[test]
        fn ball_held_by_one_constraint_slides_at_the_imposed_velocity() {
            t::ball_held_by_one_constraint_slides_at_the_imposed_velocity()
        }
        #[test]
        fn identical_rows_solve_and_share_the_multiplier() {
            t::identical_rows_solve_and_share_the_multiplier()
        }
        #[test]
        fn inconsistent_rows_are_not_converged() {
            t::inconsistent_rows_are_not_converged()
        }
        #[test]
        fn pendulum_against_a_frictionless_wall() {
            t::pendulum_against_a_frictionless_wall()
        }
        #[test]
        fn random_problems_meet_every_residual() {
            t::random_problems_meet_every_residual()
        }
        #[test]
        fn equality_rows_without_contacts() {
            t::equality_rows_without_contacts()
        }
        #[test]
        fn invalid_equality_data_is_refused() {
            t::invalid_equality_data_is_refused()
        }
    }
}
mod examples {
    mod tests {
        use coulomb::unit_tests::examples::tests as t;
        #[test]
        fn painleve_matches_paper_data() {
            t::painleve_matches_paper_data()
        }
        #[test]
        fn rigid_box_motion_gives_zero_relative_velocity() {
            t::rigid_box_motion_gives_zero_relative_velocity()
        }
        #[test]
        fn crushed_ball_normals_sum_to_minus_u0() {
            t::crushed_ball_normals_sum_to_minus_u0()
        }
        #[test]
        fn bad_arguments_are_errors() {
            t::bad_arguments_are_errors()
        }
    }
}
mod existence {
    mod tests {
        use coulomb::unit_tests::existence::tests as t;
        #[test]
        fn single_contact_local_pushing_apart_exists() {
            t::single_contact_local_pushing_apart_exists()
        }
        #[test]
        fn zero_contacts_exist() {
            t::zero_contacts_exist()
        }
        #[test]
        fn zero_delassus_and_infinite_friction_do_not_break() {
            t::zero_delassus_and_infinite_friction_do_not_break()
        }
        #[test]
        fn bad_settings_are_rejected() {
            t::bad_settings_are_rejected()
        }
        #[test]
        fn existence_check_sees_the_constraints() {
            t::existence_check_sees_the_constraints()
        }
    }
}
mod fclib {
    mod tests {
        use coulomb::unit_tests::fclib::tests as t;
        #[test]
        fn stored_evaluation_reports_the_equality_residual() {
            t::stored_evaluation_reports_the_equality_residual()
        }
    }
}
mod inner {
    mod apgd {
        mod tests {
            use coulomb::unit_tests::inner::apgd::tests as t;
            #[test]
            fn power_iteration_estimates_the_largest_eigenvalue() {
                t::power_iteration_estimates_the_largest_eigenvalue()
            }
        }
    }
    mod contact {
        mod tests {
            use coulomb::unit_tests::inner::contact::tests as t;
            #[test]
            fn one_contact_solve_satisfies_kkt() {
                t::one_contact_solve_satisfies_kkt()
            }
            #[test]
            fn one_contact_law_solve_satisfies_coulombs_law() {
                t::one_contact_law_solve_satisfies_coulombs_law()
            }
        }
    }
    mod faceted {
        mod tests {
            use coulomb::unit_tests::inner::faceted::tests as t;
            #[test]
            fn pyramid_vertices_lie_on_the_cone() {
                t::pyramid_vertices_lie_on_the_cone()
            }
            #[test]
            fn vertex_direction_is_exact() {
                t::vertex_direction_is_exact()
            }
        }
    }
    mod ipm {
        mod tests {
            use coulomb::unit_tests::inner::ipm::tests as t;
            #[test]
            fn solver_is_send() {
                t::solver_is_send()
            }
            #[test]
            fn layouts_order_rows_and_scale() {
                t::layouts_order_rows_and_scale()
            }
            #[test]
            fn single_contact_take_off_and_stick() {
                t::single_contact_take_off_and_stick()
            }
            #[test]
            fn cached_solver_matches_fresh_solve() {
                t::cached_solver_matches_fresh_solve()
            }
            #[test]
            fn bad_sizes_and_past_deadline() {
                t::bad_sizes_and_past_deadline()
            }
            #[test]
            fn projection_jacobian_matches_finite_differences() {
                t::projection_jacobian_matches_finite_differences()
            }
            #[test]
            fn polish_reaches_rounding_level_on_a_sliding_contact() {
                t::polish_reaches_rounding_level_on_a_sliding_contact()
            }
        }
    }
}
#[cfg(unix)]
mod input {
    mod tests {
        use coulomb::unit_tests::input::tests as t;
        #[test]
        fn regular_file_is_read_whole() {
            t::regular_file_is_read_whole()
        }
        #[test]
        fn fifo_is_refused_without_blocking() {
            t::fifo_is_refused_without_blocking()
        }
        #[test]
        fn dev_zero_and_directory_are_refused() {
            t::dev_zero_and_directory_are_refused()
        }
        #[test]
        fn a_socket_is_named_as_one() {
            t::a_socket_is_named_as_one()
        }
        #[test]
        fn over_the_limit_is_refused_before_reading() {
            t::over_the_limit_is_refused_before_reading()
        }
        #[test]
        fn missing_file_and_bad_text_are_typed() {
            t::missing_file_and_bad_text_are_typed()
        }
    }
}
mod law {
    mod tests {
        use coulomb::unit_tests::law::tests as t;
        #[test]
        fn lemma_3_1_on_each_branch() {
            t::lemma_3_1_on_each_branch()
        }
        #[test]
        fn violations_are_detected() {
            t::violations_are_detected()
        }
        #[test]
        fn error_scale_rule() {
            t::error_scale_rule()
        }
    }
}
mod levenberg {
    mod tests {
        use coulomb::unit_tests::levenberg::tests as t;
        #[test]
        fn levenberg_marquardt_solves_a_regular_problem_from_zero() {
            t::levenberg_marquardt_solves_a_regular_problem_from_zero()
        }
        #[test]
        fn the_escapes_solve_a_rank_deficient_problem_where_newton_stalls() {
            t::the_escapes_solve_a_rank_deficient_problem_where_newton_stalls()
        }
        #[test]
        fn a_point_outside_the_cones_is_judged_and_returned_as_its_projection() {
            t::a_point_outside_the_cones_is_judged_and_returned_as_its_projection()
        }
        #[test]
        fn a_segment_counts_from_its_first_taken_step() {
            t::a_segment_counts_from_its_first_taken_step()
        }
        #[test]
        fn bad_sizes_and_caps_give_typed_statuses() {
            t::bad_sizes_and_caps_give_typed_statuses()
        }
    }
}
mod linalg {
    mod dense {
        mod tests {
            use coulomb::unit_tests::linalg::dense::tests as t;
            #[test]
            fn solves_on_one_thread_and_on_all_to_the_same_answer() {
                t::solves_on_one_thread_and_on_all_to_the_same_answer()
            }
            #[test]
            fn bad_shapes_give_none_or_false_and_singular_gives_non_finite() {
                t::bad_shapes_give_none_or_false_and_singular_gives_non_finite()
            }
            #[test]
            fn the_storage_of_factors_takes_the_next_matrix() {
                t::the_storage_of_factors_takes_the_next_matrix()
            }
            #[test]
            fn the_parallelism_follows_the_size() {
                t::the_parallelism_follows_the_size()
            }
        }
    }
    mod skeleton {
        mod tests {
            use coulomb::unit_tests::linalg::skeleton::tests as t;
            #[test]
            fn a_low_rank_matrix_has_its_rank_found_and_the_woodbury_solve_follows_its_symmetry() {
                t::a_low_rank_matrix_has_its_rank_found_and_the_woodbury_solve_follows_its_symmetry(
                )
            }
            #[test]
            fn the_skeleton_is_exact_for_a_low_rank_w_symmetric_or_not() {
                t::the_skeleton_is_exact_for_a_low_rank_w_symmetric_or_not()
            }
            #[test]
            fn a_full_rank_matrix_has_no_skeleton() {
                t::a_full_rank_matrix_has_no_skeleton()
            }
        }
    }
    mod sparse {
        mod tests {
            use coulomb::unit_tests::linalg::sparse::tests as t;
            #[test]
            fn triplets_sum_duplicates_and_sort() {
                t::triplets_sum_duplicates_and_sort()
            }
            #[test]
            fn csr_and_transpose_agree_with_dense() {
                t::csr_and_transpose_agree_with_dense()
            }
            #[test]
            fn bad_arrays_are_reported() {
                t::bad_arrays_are_reported()
            }
            #[test]
            fn block_product_equals_entrywise_product() {
                t::block_product_equals_entrywise_product()
            }
        }
    }
}
mod line_search {
    mod tests {
        use coulomb::unit_tests::line_search::tests as t;
        #[test]
        fn the_first_sufficient_halving_is_accepted() {
            t::the_first_sufficient_halving_is_accepted()
        }
        #[test]
        fn no_decrease_a_nan_or_no_trial_exhausts() {
            t::no_decrease_a_nan_or_no_trial_exhausts()
        }
    }
}
mod multiplier {
    mod tests {
        use coulomb::unit_tests::multiplier::tests as t;
        #[test]
        fn the_method_of_multipliers_solves_a_sliding_box_on_four_corners() {
            t::the_method_of_multipliers_solves_a_sliding_box_on_four_corners()
        }
        #[test]
        fn a_finish_that_returns_a_point_ends_the_stage_and_is_tried_a_capped_number_of_times() {
            t::a_finish_that_returns_a_point_ends_the_stage_and_is_tried_a_capped_number_of_times()
        }
        #[test]
        fn several_starts_run_at_once_and_the_converged_run_is_returned() {
            t::several_starts_run_at_once_and_the_converged_run_is_returned()
        }
        #[test]
        fn gathered_columns_give_the_products_of_the_sparse_matrix() {
            t::gathered_columns_give_the_products_of_the_sparse_matrix()
        }
        #[test]
        fn the_assembled_jacobian_is_m_plus_h_b_hu_transposed() {
            t::the_assembled_jacobian_is_m_plus_h_b_hu_transposed()
        }
        #[test]
        fn an_unsolved_step_is_kept_only_when_it_lowers_the_error() {
            t::an_unsolved_step_is_kept_only_when_it_lowers_the_error()
        }
        #[test]
        fn bad_input_and_caps_give_typed_statuses() {
            t::bad_input_and_caps_give_typed_statuses()
        }
    }
}
mod newton {
    mod tests {
        use coulomb::unit_tests::newton::tests as t;
        #[test]
        fn an_exhausted_search_stops_or_takes_the_full_step_as_the_rule_says() {
            t::an_exhausted_search_stops_or_takes_the_full_step_as_the_rule_says()
        }
        #[test]
        fn least_squares_reaches_a_solution_nearby_and_never_raises_the_error() {
            t::least_squares_reaches_a_solution_nearby_and_never_raises_the_error()
        }
        #[test]
        fn jacobian_matches_finite_differences() {
            t::jacobian_matches_finite_differences()
        }
        #[test]
        fn inconsistent_sizes_take_no_step_instead_of_panicking() {
            t::inconsistent_sizes_take_no_step_instead_of_panicking()
        }
        #[test]
        fn newton_reaches_rounding_level_from_a_rough_point() {
            t::newton_reaches_rounding_level_from_a_rough_point()
        }
    }
}
mod outer {
    mod tests {
        use coulomb::unit_tests::outer::tests as t;
        #[test]
        fn the_largest_diagonal_block_of_m() {
            t::the_largest_diagonal_block_of_m()
        }
        #[test]
        fn a_cancelled_solve_ends_interrupted_with_its_error() {
            t::a_cancelled_solve_ends_interrupted_with_its_error()
        }
        #[test]
        fn a_solver_set_up_once_solves_like_fresh_solves() {
            t::a_solver_set_up_once_solves_like_fresh_solves()
        }
        #[test]
        fn a_global_solver_updates_f_and_w_like_a_fresh_problem() {
            t::a_global_solver_updates_f_and_w_like_a_fresh_problem()
        }
        #[test]
        fn a_rank_deficient_local_problem_tries_the_interior_point_method_first() {
            t::a_rank_deficient_local_problem_tries_the_interior_point_method_first()
        }
        #[test]
        fn a_rigid_global_problem_tries_the_interior_point_method_first() {
            t::a_rigid_global_problem_tries_the_interior_point_method_first()
        }
        #[test]
        fn the_multipliers_apply_to_rigid_problems_whose_skeleton_reproduces_w() {
            t::the_multipliers_apply_to_rigid_problems_whose_skeleton_reproduces_w()
        }
        #[test]
        fn an_unconverged_solve_returns_its_lowest_error_iterate() {
            t::an_unconverged_solve_returns_its_lowest_error_iterate()
        }
        #[test]
        fn a_stage_hands_its_stall_to_the_lm_end_game() {
            t::a_stage_hands_its_stall_to_the_lm_end_game()
        }
    }
    mod anderson {
        mod tests {
            use coulomb::unit_tests::outer::anderson::tests as t;
            #[test]
            fn mixing_solves_an_affine_fixed_point_in_a_few_steps() {
                t::mixing_solves_an_affine_fixed_point_in_a_few_steps()
            }
            #[test]
            fn restart_drops_the_differences_and_keeps_the_last_point() {
                t::restart_drops_the_differences_and_keeps_the_last_point()
            }
        }
    }
    mod fixed_point {
        mod tests {
            use coulomb::unit_tests::outer::fixed_point::tests as t;
            #[test]
            fn anderson_accelerates_a_linear_contraction() {
                t::anderson_accelerates_a_linear_contraction()
            }
            #[test]
            fn shift_touches_normal_components_only() {
                t::shift_touches_normal_components_only()
            }
        }
    }
    mod fused {
        mod tests {
            use coulomb::unit_tests::outer::fused::tests as t;
            #[test]
            fn anderson_mixing_shortens_gauss_seidel_on_rank_deficient_problems() {
                t::anderson_mixing_shortens_gauss_seidel_on_rank_deficient_problems()
            }
        }
    }
}
mod plan {
    mod tests {
        use coulomb::unit_tests::plan::tests as t;
        #[test]
        fn the_paper_is_one_step_and_the_default_follows_the_structure() {
            t::the_paper_is_one_step_and_the_default_follows_the_structure()
        }
        #[test]
        fn a_granular_step_runs_gauss_seidel_first_and_other_problems_keep_their_plan() {
            t::a_granular_step_runs_gauss_seidel_first_and_other_problems_keep_their_plan()
        }
    }
}
mod problem {
    mod tests {
        use coulomb::unit_tests::problem::tests as t;
        #[test]
        fn paper_convention_round_trip() {
            t::paper_convention_round_trip()
        }
        #[test]
        fn zero_contacts_is_valid() {
            t::zero_contacts_is_valid()
        }
        #[test]
        fn every_validation_error_is_reported() {
            t::every_validation_error_is_reported()
        }
    }
}
mod proximal {
    mod tests {
        use coulomb::unit_tests::proximal::tests as t;
        #[test]
        fn the_proximal_point_solves_a_rank_deficient_problem_and_reports_the_stored_error() {
            t::the_proximal_point_solves_a_rank_deficient_problem_and_reports_the_stored_error()
        }
        #[test]
        fn a_regularized_problem_not_solved_leaves_the_centre_and_is_counted() {
            t::a_regularized_problem_not_solved_leaves_the_centre_and_is_counted()
        }
        #[test]
        fn bad_sizes_caps_and_deadlines_give_typed_statuses() {
            t::bad_sizes_caps_and_deadlines_give_typed_statuses()
        }
    }
}
mod settings {
    mod tests {
        use coulomb::unit_tests::settings::tests as t;
        #[test]
        fn a_zero_stagnation_window_is_refused() {
            t::a_zero_stagnation_window_is_refused()
        }
        #[test]
        fn method_names_round_trip() {
            t::method_names_round_trip()
        }
        #[test]
        fn presets_validate_and_bad_tuning_is_refused() {
            t::presets_validate_and_bad_tuning_is_refused()
        }
        #[test]
        fn inner_tolerance_stays_between_floor_and_ceiling() {
            t::inner_tolerance_stays_between_floor_and_ceiling()
        }
    }
}
mod solution {
    mod tests {
        use coulomb::unit_tests::solution::tests as t;
        #[test]
        fn status_names_match_their_serialization() {
            t::status_names_match_their_serialization()
        }
    }
}
