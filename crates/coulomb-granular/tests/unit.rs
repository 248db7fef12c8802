//! The unit tests of `coulomb_granular` (modules `#[cfg(feature = "unit-tests")] pub mod tests`
//! of its library), each run by a `#[test]` at its module's path: compiled once, with the
//! library, instead of in a second build of the whole crate as a test harness
//! (docs/testing.md). Written by `scripts/unit_tests.py`; do not edit.

mod bodies {
    mod dynamics {
        mod tests {
            use coulomb_granular::unit_tests::bodies::dynamics::tests as t;
            #[test]
            fn free_rotation_conserves_energy_and_momentum_per_step() {
                t::free_rotation_conserves_energy_and_momentum_per_step()
            }
            #[test]
            fn exponential_map_rotates_about_the_body_axis() {
                t::exponential_map_rotates_about_the_body_axis()
            }
        }
    }
    mod joints {
        mod tests {
            use coulomb_granular::unit_tests::bodies::joints::tests as t;
            #[test]
            fn spd_solve_handles_dependent_rows() {
                t::spd_solve_handles_dependent_rows()
            }
            #[test]
            fn rotation_vector_of_a_quarter_turn() {
                t::rotation_vector_of_a_quarter_turn()
            }
        }
    }
    mod mesh {
        mod tests {
            use coulomb_granular::unit_tests::bodies::mesh::tests as t;
            #[test]
            fn closest_points_by_region() {
                t::closest_points_by_region()
            }
            #[test]
            fn a_query_from_inside_a_query_gets_the_same_contacts() {
                t::a_query_from_inside_a_query_gets_the_same_contacts()
            }
            #[test]
            fn box_mesh_is_closed_and_contains_its_inside() {
                t::box_mesh_is_closed_and_contains_its_inside()
            }
            #[test]
            fn bad_meshes_are_refused() {
                t::bad_meshes_are_refused()
            }
            #[test]
            fn shared_edges_and_vertices_give_one_contact() {
                t::shared_edges_and_vertices_give_one_contact()
            }
            #[test]
            fn facets_closer_than_two_degrees_give_one_contact_at_a_concave_edge() {
                t::facets_closer_than_two_degrees_give_one_contact_at_a_concave_edge()
            }
        }
    }
    mod shape {
        mod tests {
            use coulomb_granular::unit_tests::bodies::shape::tests as t;
            #[test]
            fn mass_properties_match_the_closed_forms() {
                t::mass_properties_match_the_closed_forms()
            }
            #[test]
            fn a_compound_combines_its_parts() {
                t::a_compound_combines_its_parts()
            }
            #[test]
            fn tessellations_are_closed_and_outward() {
                t::tessellations_are_closed_and_outward()
            }
            #[test]
            fn bad_shapes_are_refused_with_what_is_wrong() {
                t::bad_shapes_are_refused_with_what_is_wrong()
            }
            #[test]
            fn rotate_matches_parry() {
                t::rotate_matches_parry()
            }
            #[test]
            fn shapes_round_trip_through_toml_and_json() {
                t::shapes_round_trip_through_toml_and_json()
            }
            #[test]
            fn hull_widths_by_walking_equal_the_scan() {
                t::hull_widths_by_walking_equal_the_scan()
            }
            #[test]
            fn random_and_degenerate_point_sets_never_panic() {
                t::random_and_degenerate_point_sets_never_panic()
            }
            #[test]
            fn a_large_convex_polyhedron_is_checked_and_a_dent_refused() {
                t::a_large_convex_polyhedron_is_checked_and_a_dent_refused()
            }
            #[test]
            fn bounding_radius_holds_the_shape_and_scales_with_it() {
                t::bounding_radius_holds_the_shape_and_scales_with_it()
            }
        }
    }
    mod world {
        mod tests {
            use coulomb_granular::unit_tests::bodies::world::tests as t;
            #[test]
            fn plane_and_cylinder_gaps() {
                t::plane_and_cylinder_gaps()
            }
            #[test]
            fn rectangle_edge_and_face() {
                t::rectangle_edge_and_face()
            }
            #[test]
            fn motions() {
                t::motions()
            }
            #[test]
            fn box_container_walls_and_open_top() {
                t::box_container_walls_and_open_top()
            }
            #[test]
            fn solid_box_faces_edges_and_inside() {
                t::solid_box_faces_edges_and_inside()
            }
            #[test]
            fn silo_with_orifice_and_solid_cylinder() {
                t::silo_with_orifice_and_solid_cylinder()
            }
            #[test]
            fn sphere_obstacles_inside_and_outside() {
                t::sphere_obstacles_inside_and_outside()
            }
            #[test]
            fn translating_and_rotating_obstacles_move_rigidly() {
                t::translating_and_rotating_obstacles_move_rigidly()
            }
            #[test]
            fn mesh_square_is_a_plane_to_a_sphere_on_it() {
                t::mesh_square_is_a_plane_to_a_sphere_on_it()
            }
            #[test]
            fn material_table_is_symmetric_and_checked() {
                t::material_table_is_symmetric_and_checked()
            }
            #[test]
            fn a_rotating_mesh_drum_is_the_rotating_cylinder_up_to_its_chords() {
                t::a_rotating_mesh_drum_is_the_rotating_cylinder_up_to_its_chords()
            }
        }
    }
}
mod collision {
    mod contact {
        mod tests {
            use coulomb_granular::unit_tests::collision::contact::tests as t;
            #[test]
            fn a_partner_reads_and_writes_the_rigid_records_form() {
                t::a_partner_reads_and_writes_the_rigid_records_form()
            }
            #[test]
            fn grid_finds_the_same_pairs_as_brute_force() {
                t::grid_finds_the_same_pairs_as_brute_force()
            }
            #[test]
            fn resting_spheres_find_floor_contacts_that_only_gravity_or_the_floor_closes() {
                t::resting_spheres_find_floor_contacts_that_only_gravity_or_the_floor_closes()
            }
            #[test]
            fn detection_frames_and_activation() {
                t::detection_frames_and_activation()
            }
            #[test]
            fn a_floor_of_fixed_balls_is_found_through_the_obstacle_grid() {
                t::a_floor_of_fixed_balls_is_found_through_the_obstacle_grid()
            }
        }
    }
    mod manifold {
        mod tests {
            use coulomb_granular::unit_tests::collision::manifold::tests as t;
            #[test]
            fn the_caches_handed_on_are_those_remove_gives() {
                t::the_caches_handed_on_are_those_remove_gives()
            }
            #[test]
            fn ball_pairs_match_parry_on_random_pairs() {
                t::ball_pairs_match_parry_on_random_pairs()
            }
            #[test]
            fn stored_pair_caches_refuse_an_obstacle_feature() {
                t::stored_pair_caches_refuse_an_obstacle_feature()
            }
            #[test]
            fn a_box_of_balls_and_cuboids_gives_parry_points_in_parry_order() {
                t::a_box_of_balls_and_cuboids_gives_parry_points_in_parry_order()
            }
            #[test]
            fn a_ball_sliding_then_rolling_on_the_floor_moves_as_with_parry() {
                t::a_ball_sliding_then_rolling_on_the_floor_moves_as_with_parry()
            }
            #[test]
            fn two_balls_colliding_above_the_floor_move_as_with_parry() {
                t::two_balls_colliding_above_the_floor_move_as_with_parry()
            }
            #[test]
            fn a_ball_pile_with_a_cuboid_gives_the_same_bits_on_one_and_two_threads() {
                t::a_ball_pile_with_a_cuboid_gives_the_same_bits_on_one_and_two_threads()
            }
        }
    }
    mod tunnelling {
        mod tests {
            use coulomb_granular::unit_tests::collision::tunnelling::tests as t;
            #[test]
            fn a_thin_wall_is_crossed_beyond_the_smallest_radius() {
                t::a_thin_wall_is_crossed_beyond_the_smallest_radius()
            }
            #[test]
            fn the_obstacle_speed_adds_to_the_sphere_speed() {
                t::the_obstacle_speed_adds_to_the_sphere_speed()
            }
            #[test]
            fn solids_have_their_thickness_and_one_sided_shapes_none() {
                t::solids_have_their_thickness_and_one_sided_shapes_none()
            }
        }
    }
}
#[cfg(feature = "mpi")]
mod distributed {
    mod grid {
        mod tests {
            use coulomb_granular::unit_tests::distributed::grid::tests as t;
            #[test]
            fn grid_cells_targets_and_neighbours() {
                t::grid_cells_targets_and_neighbours()
            }
        }
    }
    mod slab {
        mod tests {
            use coulomb_granular::unit_tests::distributed::slab::tests as t;
            #[test]
            fn owners_and_ghost_targets() {
                t::owners_and_ghost_targets()
            }
            #[test]
            fn quantiles_split_the_beads_evenly() {
                t::quantiles_split_the_beads_evenly()
            }
            #[test]
            fn quantiles_of_weighted_histograms_split_the_work() {
                t::quantiles_of_weighted_histograms_split_the_work()
            }
        }
    }
    mod subdomain {
        mod tests {
            use coulomb_granular::unit_tests::distributed::subdomain::tests as t;
            #[test]
            fn distributed_subdomain_sweeps_converge_and_keep_the_balance() {
                t::distributed_subdomain_sweeps_converge_and_keep_the_balance()
            }
            #[test]
            fn split_sweeps_of_two_subdomains_keep_the_balance_and_converge() {
                t::split_sweeps_of_two_subdomains_keep_the_balance_and_converge()
            }
        }
    }
}
mod io {
    mod checkpoint {
        mod tests {
            use coulomb_granular::unit_tests::io::checkpoint::tests as t;
            #[test]
            fn restart_is_bitwise_nsgs() {
                t::restart_is_bitwise_nsgs()
            }
            #[test]
            fn restart_is_bitwise_with_rolling_friction() {
                t::restart_is_bitwise_with_rolling_friction()
            }
            #[test]
            fn every_shape_and_motion_round_trips() {
                t::every_shape_and_motion_round_trips()
            }
            #[test]
            fn truncated_files_are_refused() {
                t::truncated_files_are_refused()
            }
            #[test]
            fn flipped_bytes_never_give_a_different_state() {
                t::flipped_bytes_never_give_a_different_state()
            }
            #[test]
            fn other_versions_and_formats_are_refused() {
                t::other_versions_and_formats_are_refused()
            }
            #[test]
            fn out_of_range_indices_are_refused() {
                t::out_of_range_indices_are_refused()
            }
            #[test]
            fn non_finite_parameters_are_not_written() {
                t::non_finite_parameters_are_not_written()
            }
            #[test]
            fn a_changed_value_is_named_by_its_dataset() {
                t::a_changed_value_is_named_by_its_dataset()
            }
            #[test]
            fn a_dataset_of_the_wrong_length_is_the_one_named() {
                t::a_dataset_of_the_wrong_length_is_the_one_named()
            }
        }
    }
    mod output {
        mod tests {
            use coulomb_granular::unit_tests::io::output::tests as t;
            #[test]
            fn binary_frames_hold_the_exact_positions_and_are_smaller() {
                t::binary_frames_hold_the_exact_positions_and_are_smaller()
            }
            #[test]
            fn frames_split_over_processes_hold_the_arrays_of_one_process() {
                t::frames_split_over_processes_hold_the_arrays_of_one_process()
            }
            #[test]
            fn obstacle_surfaces_lie_on_the_obstacles_and_cover_the_beads() {
                t::obstacle_surfaces_lie_on_the_obstacles_and_cover_the_beads()
            }
            #[test]
            fn moving_obstacles_are_drawn_at_their_place() {
                t::moving_obstacles_are_drawn_at_their_place()
            }
            #[test]
            fn writer_keeps_one_obstacles_file_when_nothing_moves_and_resumes() {
                t::writer_keeps_one_obstacles_file_when_nothing_moves_and_resumes()
            }
            #[test]
            fn sphere_frames_are_those_of_the_sphere_only_writer() {
                t::sphere_frames_are_those_of_the_sphere_only_writer()
            }
            #[test]
            fn stats_continue_after_a_restart() {
                t::stats_continue_after_a_restart()
            }
            #[test]
            fn rigid_frames_hold_each_body_as_its_polygons() {
                t::rigid_frames_hold_each_body_as_its_polygons()
            }
            #[test]
            fn rigid_frames_hold_balls_as_points_with_radii_in_the_same_collection() {
                t::rigid_frames_hold_balls_as_points_with_radii_in_the_same_collection()
            }
        }
    }
    #[cfg(unix)]
    mod output_dir {
        mod tests {
            use coulomb_granular::unit_tests::io::output_dir::tests as t;
            #[test]
            fn links_planted_in_the_folder_are_refused_not_written_through() {
                t::links_planted_in_the_folder_are_refused_not_written_through()
            }
        }
    }
    mod report {
        mod tests {
            use coulomb_granular::unit_tests::io::report::tests as t;
            #[test]
            fn the_csv_row_has_one_field_per_column() {
                t::the_csv_row_has_one_field_per_column()
            }
        }
    }
    mod rigid_checkpoint {
        mod tests {
            use coulomb_granular::unit_tests::io::rigid_checkpoint::tests as t;
            #[test]
            fn restart_gives_the_same_bits() {
                t::restart_gives_the_same_bits()
            }
            #[test]
            fn the_switch_to_plain_sweeps_is_restored() {
                t::the_switch_to_plain_sweeps_is_restored()
            }
            #[test]
            fn the_library_settings_are_restored() {
                t::the_library_settings_are_restored()
            }
            #[test]
            fn the_step_switches_are_restored() {
                t::the_step_switches_are_restored()
            }
            #[test]
            fn the_shipped_wall_restarts_to_the_bit() {
                t::the_shipped_wall_restarts_to_the_bit()
            }
            #[test]
            fn a_scene_with_joints_restarts_to_the_bit() {
                t::a_scene_with_joints_restarts_to_the_bit()
            }
            #[test]
            fn version_one_files_read_without_joints() {
                t::version_one_files_read_without_joints()
            }
            #[test]
            fn contacts_are_the_sphere_checkpoints_and_version_5_json_still_reads() {
                t::contacts_are_the_sphere_checkpoints_and_version_5_json_still_reads()
            }
            #[test]
            fn pairs_written_as_a_and_b_read_as_the_same_materials() {
                t::pairs_written_as_a_and_b_read_as_the_same_materials()
            }
            #[test]
            fn damaged_or_foreign_files_are_refused_with_a_reason() {
                t::damaged_or_foreign_files_are_refused_with_a_reason()
            }
            #[test]
            fn a_state_that_does_not_fit_the_world_is_refused() {
                t::a_state_that_does_not_fit_the_world_is_refused()
            }
            #[test]
            fn errors_name_the_dataset_that_is_wrong() {
                t::errors_name_the_dataset_that_is_wrong()
            }
        }
    }
}
mod math {
    mod tests {
        use coulomb_granular::unit_tests::math::tests as t;
        #[test]
        fn shown_as_an_array() {
            t::shown_as_an_array()
        }
        #[test]
        fn tangent_basis_is_orthonormal_and_right_handed() {
            t::tangent_basis_is_orthonormal_and_right_handed()
        }
    }
}
mod run {
    mod tests {
        use coulomb_granular::unit_tests::run::tests as t;
        #[test]
        fn the_stop_reason_tells_rest_cap_steps_and_signals_apart() {
            t::the_stop_reason_tells_rest_cap_steps_and_signals_apart()
        }
    }
}
mod scene {
    mod builtin {
        mod tests {
            use coulomb_granular::unit_tests::scene::builtin::tests as t;
            #[test]
            fn scenes_are_deterministic_and_start_without_overlap() {
                t::scenes_are_deterministic_and_start_without_overlap()
            }
            #[test]
            fn streamed_beads_are_the_built_ones() {
                t::streamed_beads_are_the_built_ones()
            }
            #[test]
            fn builtin_models_are_valid_scenes() {
                t::builtin_models_are_valid_scenes()
            }
            #[test]
            fn calibrated_box_grows_with_the_beads_and_holds_them() {
                t::calibrated_box_grows_with_the_beads_and_holds_them()
            }
        }
    }
    mod file {
        mod tests {
            use coulomb_granular::unit_tests::scene::file::tests as t;
            #[test]
            fn extra_array_elements_are_refused_with_their_place() {
                t::extra_array_elements_are_refused_with_their_place()
            }
            #[test]
            fn a_huge_fill_or_inlet_is_refused_before_building() {
                t::a_huge_fill_or_inlet_is_refused_before_building()
            }
            #[test]
            fn an_overfull_random_fill_is_refused_or_keeps_what_fits() {
                t::an_overfull_random_fill_is_refused_or_keeps_what_fits()
            }
            #[test]
            fn streamed_spheres_are_the_built_ones() {
                t::streamed_spheres_are_the_built_ones()
            }
            #[test]
            fn unknown_keys_are_refused_with_file_line_and_column() {
                t::unknown_keys_are_refused_with_file_line_and_column()
            }
            #[test]
            fn a_pair_naming_an_unknown_material_is_refused_where_it_is() {
                t::a_pair_naming_an_unknown_material_is_refused_where_it_is()
            }
            #[test]
            fn bad_values_are_refused() {
                t::bad_values_are_refused()
            }
            #[test]
            fn inline_spheres_materials_and_pairs() {
                t::inline_spheres_materials_and_pairs()
            }
            #[test]
            fn files_next_to_the_scene_fixed_spheres_and_a_mesh_obstacle() {
                t::files_next_to_the_scene_fixed_spheres_and_a_mesh_obstacle()
            }
            #[test]
            fn shaped_groups_become_body_specs_in_file_order() {
                t::shaped_groups_become_body_specs_in_file_order()
            }
            #[test]
            fn bad_shaped_groups_are_refused_where_they_are() {
                t::bad_shaped_groups_are_refused_where_they_are()
            }
            #[test]
            fn obstacles_laws_and_steps_are_the_models_types_validated_once() {
                t::obstacles_laws_and_steps_are_the_models_types_validated_once()
            }
            #[test]
            fn line_column_counts_characters() {
                t::line_column_counts_characters()
            }
        }
    }
    mod generate {
        mod tests {
            use coulomb_granular::unit_tests::scene::generate::tests as t;
            #[test]
            fn a_huge_rate_is_bounded_by_what_fits_in_the_region() {
                t::a_huge_rate_is_bounded_by_what_fits_in_the_region()
            }
            #[test]
            fn lattice_fill_of_a_box_is_deterministic_counted_and_free_of_overlaps() {
                t::lattice_fill_of_a_box_is_deterministic_counted_and_free_of_overlaps()
            }
            #[test]
            fn random_addition_fills_a_cylinder_without_overlap_and_respects_obstacles() {
                t::random_addition_fills_a_cylinder_without_overlap_and_respects_obstacles()
            }
            #[test]
            fn predicate_region_fills_the_inside_only() {
                t::predicate_region_fills_the_inside_only()
            }
            #[test]
            fn distribution_moments() {
                t::distribution_moments()
            }
            #[test]
            fn psd_sampling_matches_the_table() {
                t::psd_sampling_matches_the_table()
            }
            #[test]
            fn bad_distributions_are_refused() {
                t::bad_distributions_are_refused()
            }
            #[test]
            fn inlet_emits_by_rate_without_overlap_and_without_state() {
                t::inlet_emits_by_rate_without_overlap_and_without_state()
            }
            #[test]
            fn an_inlet_shape_adds_only_a_rotation_drawn_after_the_sphere() {
                t::an_inlet_shape_adds_only_a_rotation_drawn_after_the_sphere()
            }
            #[test]
            fn mass_rate_inlet_never_exceeds_its_mass() {
                t::mass_rate_inlet_never_exceeds_its_mass()
            }
        }
    }
    mod import {
        mod tests {
            use coulomb_granular::unit_tests::scene::import::tests as t;
            #[test]
            fn csv_particles_with_velocities_and_materials() {
                t::csv_particles_with_velocities_and_materials()
            }
            #[test]
            fn bad_csv_files_name_the_file_and_line() {
                t::bad_csv_files_name_the_file_and_line()
            }
            #[test]
            fn npy_particles() {
                t::npy_particles()
            }
            #[test]
            fn npy_headers_orders_and_byte_orders() {
                t::npy_headers_orders_and_byte_orders()
            }
            #[test]
            fn streamed_particles_are_the_read_ones() {
                t::streamed_particles_are_the_read_ones()
            }
            #[test]
            fn obj_cube_is_closed_oriented_and_answers_inside() {
                t::obj_cube_is_closed_oriented_and_answers_inside()
            }
            #[test]
            fn stl_binary_and_ascii_read_the_same_triangle() {
                t::stl_binary_and_ascii_read_the_same_triangle()
            }
            #[test]
            fn bad_meshes_are_refused_with_the_path() {
                t::bad_meshes_are_refused_with_the_path()
            }
        }
    }
    mod model {
        mod tests {
            use coulomb_granular::unit_tests::scene::model::tests as t;
            #[test]
            fn a_model_builds_and_round_trips_through_serde() {
                t::a_model_builds_and_round_trips_through_serde()
            }
            #[test]
            fn bad_input_gives_typed_errors() {
                t::bad_input_gives_typed_errors()
            }
            #[test]
            fn spheres_overlapping_an_obstacle_are_refused_and_relaxed() {
                t::spheres_overlapping_an_obstacle_are_refused_and_relaxed()
            }
            #[test]
            fn overlaps_and_containment_are_refused_and_overlaps_relaxed() {
                t::overlaps_and_containment_are_refused_and_overlaps_relaxed()
            }
        }
    }
    mod rigid {
        mod tests {
            use coulomb_granular::unit_tests::scene::rigid::tests as t;
            #[test]
            fn a_box_and_a_ball_on_the_floor_build_and_step() {
                t::a_box_and_a_ball_on_the_floor_build_and_step()
            }
            #[test]
            fn overrides_and_bad_bodies() {
                t::overrides_and_bad_bodies()
            }
        }
    }
    mod save {
        mod tests {
            use coulomb_granular::unit_tests::scene::save::tests as t;
            #[test]
            fn a_saved_sphere_scene_builds_the_same_world_to_the_bit() {
                t::a_saved_sphere_scene_builds_the_same_world_to_the_bit()
            }
            #[test]
            fn a_saved_rigid_scene_reads_back_its_bodies() {
                t::a_saved_rigid_scene_reads_back_its_bodies()
            }
            #[test]
            fn what_a_scene_file_cannot_hold_is_refused_and_a_device_is_not_replaced() {
                t::what_a_scene_file_cannot_hold_is_refused_and_a_device_is_not_replaced()
            }
        }
    }
    mod urdf {
        mod tests {
            use coulomb_granular::unit_tests::scene::urdf::tests as t;
            #[test]
            fn rpy_is_fixed_axis_roll_pitch_yaw() {
                t::rpy_is_fixed_axis_roll_pitch_yaw()
            }
        }
    }
    mod urdf_reader {
        mod tests {
            use coulomb_granular::unit_tests::scene::urdf_reader::tests as t;
            #[test]
            fn omitted_parts_take_urdf_defaults() {
                t::omitted_parts_take_urdf_defaults()
            }
            #[test]
            fn a_missing_required_attribute_is_named_with_its_line() {
                t::a_missing_required_attribute_is_named_with_its_line()
            }
            #[test]
            fn an_unknown_joint_type_or_shape_is_refused() {
                t::an_unknown_joint_type_or_shape_is_refused()
            }
            #[test]
            fn malformed_xml_is_refused_with_its_line() {
                t::malformed_xml_is_refused_with_its_line()
            }
        }
    }
}
mod step {
    mod assembly {
        mod tests {
            use coulomb_granular::unit_tests::step::assembly::tests as t;
            #[test]
            fn h_and_w_give_the_relative_velocities() {
                t::h_and_w_give_the_relative_velocities()
            }
            #[test]
            fn restitution_enters_the_normal_rows_only_when_approaching() {
                t::restitution_enters_the_normal_rows_only_when_approaching()
            }
            #[test]
            fn mass_and_free_momentum() {
                t::mass_and_free_momentum()
            }
        }
    }
    mod coarse {
        mod tests {
            use coulomb_granular::unit_tests::step::coarse::tests as t;
            #[test]
            fn the_aggregates_of_a_column_are_its_layers() {
                t::the_aggregates_of_a_column_are_its_layers()
            }
            #[test]
            fn a_column_of_ten_spheres_converges_in_fewer_sweeps() {
                t::a_column_of_ten_spheres_converges_in_fewer_sweeps()
            }
            #[test]
            fn a_six_layer_stack_converges_in_fewer_sweeps() {
                t::a_six_layer_stack_converges_in_fewer_sweeps()
            }
            #[test]
            fn the_cells_of_a_column_give_one_interface_per_cell_boundary() {
                t::the_cells_of_a_column_give_one_interface_per_cell_boundary()
            }
            #[test]
            fn the_smoothing_estimate_of_a_column_is_a_spectral_radius() {
                t::the_smoothing_estimate_of_a_column_is_a_spectral_radius()
            }
            #[test]
            fn cells_of_one_diameter_solve_a_column_at_once() {
                t::cells_of_one_diameter_solve_a_column_at_once()
            }
            #[test]
            fn smoothed_cells_of_two_diameters_help_a_column_a_little() {
                t::smoothed_cells_of_two_diameters_help_a_column_a_little()
            }
            #[test]
            fn a_random_heap_converges_with_every_coarse_space() {
                t::a_random_heap_converges_with_every_coarse_space()
            }
        }
    }
    mod colour_progress {
        mod tests {
            use coulomb_granular::unit_tests::step::colour_progress::tests as t;
            #[test]
            fn colours_run_in_order_and_every_chunk_once() {
                t::colours_run_in_order_and_every_chunk_once()
            }
        }
    }
    mod nsgs {
        mod tests {
            use coulomb_granular::unit_tests::step::nsgs::tests as t;
            #[test]
            fn rows_are_the_assembled_problem() {
                t::rows_are_the_assembled_problem()
            }
            #[test]
            fn error_agrees_with_the_library_on_a_heap() {
                t::error_agrees_with_the_library_on_a_heap()
            }
            #[test]
            fn colouring_is_valid_and_checked() {
                t::colouring_is_valid_and_checked()
            }
            #[test]
            fn colouring_past_64_colours_on_one_sphere() {
                t::colouring_past_64_colours_on_one_sphere()
            }
            #[test]
            fn same_numbers_for_one_and_two_threads() {
                t::same_numbers_for_one_and_two_threads()
            }
            #[test]
            fn simulation_is_deterministic_across_thread_counts() {
                t::simulation_is_deterministic_across_thread_counts()
            }
            #[test]
            fn a_step_gauss_seidel_leaves_above_tol_is_finished_by_the_library() {
                t::a_step_gauss_seidel_leaves_above_tol_is_finished_by_the_library()
            }
            #[test]
            fn without_the_library_finish_a_step_depends_on_gauss_seidel_alone() {
                t::without_the_library_finish_a_step_depends_on_gauss_seidel_alone()
            }
            #[test]
            fn caps_give_typed_statuses() {
                t::caps_give_typed_statuses()
            }
        }
    }
    mod projection {
        mod tests {
            use coulomb_granular::unit_tests::step::projection::tests as t;
            #[test]
            fn projection_lifts_a_sunk_sphere_out_of_a_cylinder_exactly() {
                t::projection_lifts_a_sunk_sphere_out_of_a_cylinder_exactly()
            }
            #[test]
            fn projection_separates_a_stack_with_minimum_displacement() {
                t::projection_separates_a_stack_with_minimum_displacement()
            }
            #[test]
            fn inelastic_projection_exports_the_impulse_it_applies() {
                t::inelastic_projection_exports_the_impulse_it_applies()
            }
            #[test]
            fn stored_settings_without_velocities_read_as_before() {
                t::stored_settings_without_velocities_read_as_before()
            }
            #[test]
            fn coloured_projection_is_the_same_for_one_and_two_threads() {
                t::coloured_projection_is_the_same_for_one_and_two_threads()
            }
        }
    }
    mod rigid {
        mod tests {
            use coulomb_granular::unit_tests::step::rigid::tests as t;
            #[test]
            fn refuses_bad_quaternions_without_normalizing() {
                t::refuses_bad_quaternions_without_normalizing()
            }
            #[test]
            fn refuses_bad_mass_state_and_material() {
                t::refuses_bad_mass_state_and_material()
            }
            #[test]
            fn refuses_interpenetrating_bodies_with_count_and_depth() {
                t::refuses_interpenetrating_bodies_with_count_and_depth()
            }
            #[test]
            fn set_positions_moves_the_shape_frames_and_same_positions_keep_the_bits() {
                t::set_positions_moves_the_shape_frames_and_same_positions_keep_the_bits()
            }
            #[test]
            fn the_solver_settings_and_keep_problem_can_be_changed() {
                t::the_solver_settings_and_keep_problem_can_be_changed()
            }
            #[test]
            fn free_fall_is_exact_and_the_problem_is_kept() {
                t::free_fall_is_exact_and_the_problem_is_kept()
            }
            #[test]
            fn warm_start_matches_manifold_points_across_steps() {
                t::warm_start_matches_manifold_points_across_steps()
            }
            #[test]
            fn a_stalled_step_is_handed_to_the_library_on_the_global_problem() {
                t::a_stalled_step_is_handed_to_the_library_on_the_global_problem()
            }
            #[test]
            fn the_quick_library_finish_solves_a_redundant_face_contact() {
                t::the_quick_library_finish_solves_a_redundant_face_contact()
            }
            #[test]
            fn a_quick_finish_switches_the_world_to_plain_sweeps() {
                t::a_quick_finish_switches_the_world_to_plain_sweeps()
            }
            #[test]
            fn parallel_evaluation_is_the_sequential_scatter_bit_for_bit() {
                t::parallel_evaluation_is_the_sequential_scatter_bit_for_bit()
            }
            #[test]
            fn over_relaxation_finishes_a_ball_column_in_fewer_sweeps() {
                t::over_relaxation_finishes_a_ball_column_in_fewer_sweeps()
            }
            #[test]
            fn same_input_same_bits() {
                t::same_input_same_bits()
            }
            #[test]
            fn a_body_too_fast_for_the_step_is_warned_about() {
                t::a_body_too_fast_for_the_step_is_warned_about()
            }
        }
        mod correct {
            mod tests {
                use coulomb_granular::unit_tests::step::rigid::correct::tests as t;
                #[test]
                fn the_coloured_correction_is_the_sequential_loop_bit_for_bit() {
                    t::the_coloured_correction_is_the_sequential_loop_bit_for_bit()
                }
                #[test]
                fn large_corrections_have_parallel_colours() {
                    t::large_corrections_have_parallel_colours()
                }
            }
        }
        mod equality {
            mod tests {
                use coulomb_granular::unit_tests::step::rigid::equality::tests as t;
                #[test]
                fn a_chain_of_point_rows_is_solved_in_one_update() {
                    t::a_chain_of_point_rows_is_solved_in_one_update()
                }
                #[test]
                fn dependent_rows_get_no_update_and_the_others_hold() {
                    t::dependent_rows_get_no_update_and_the_others_hold()
                }
            }
        }
        mod nsgs {
            mod tests {
                use coulomb_granular::unit_tests::step::rigid::nsgs::tests as t;
                #[test]
                fn isotropic_law_solves_the_one_contact_law() {
                    t::isotropic_law_solves_the_one_contact_law()
                }
                #[test]
                fn ball_contacts_take_the_closed_form() {
                    t::ball_contacts_take_the_closed_form()
                }
            }
        }
        mod relax {
            mod tests {
                use coulomb_granular::unit_tests::step::rigid::relax::tests as t;
                #[test]
                fn a_sunken_stack_is_relaxed_apart() {
                    t::a_sunken_stack_is_relaxed_apart()
                }
                #[test]
                fn a_relaxation_past_its_time_cap_is_refused() {
                    t::a_relaxation_past_its_time_cap_is_refused()
                }
                #[test]
                fn a_budget_too_small_is_refused() {
                    t::a_budget_too_small_is_refused()
                }
            }
        }
    }
    mod rolling {
        mod tests {
            use coulomb_granular::unit_tests::step::rolling::tests as t;
            #[test]
            fn ball_projection_and_residual() {
                t::ball_projection_and_residual()
            }
            #[test]
            fn six_by_six_solve() {
                t::six_by_six_solve()
            }
            #[test]
            fn ball_qp_is_the_minimizer_over_the_ball() {
                t::ball_qp_is_the_minimizer_over_the_ball()
            }
            #[test]
            fn stick_roll_solves_both_laws_on_a_floor_contact() {
                t::stick_roll_solves_both_laws_on_a_floor_contact()
            }
            #[test]
            fn inverse_of_a_3x3() {
                t::inverse_of_a_3x3()
            }
        }
    }
    mod subspace {
        mod tests {
            use coulomb_granular::unit_tests::step::subspace::tests as t;
            #[test]
            fn a_column_of_spheres_converges_in_far_fewer_sweeps() {
                t::a_column_of_spheres_converges_in_far_fewer_sweeps()
            }
            #[test]
            fn a_six_layer_stack_converges_in_far_fewer_sweeps() {
                t::a_six_layer_stack_converges_in_far_fewer_sweeps()
            }
            #[test]
            fn same_bits_on_one_and_two_threads() {
                t::same_bits_on_one_and_two_threads()
            }
        }
    }
}
mod validation {
    mod tests {
        use coulomb_granular::unit_tests::validation::tests as t;
        #[test]
        fn a_check_passes_only_on_finite_values_within_tolerance() {
            t::a_check_passes_only_on_finite_values_within_tolerance()
        }
        #[test]
        fn solid_fraction_of_known_arrangements() {
            t::solid_fraction_of_known_arrangements()
        }
    }
    mod laws {
        mod tests {
            use coulomb_granular::unit_tests::validation::laws::tests as t;
            #[test]
            fn the_law_scene_files_parse_and_build() {
                t::the_law_scene_files_parse_and_build()
            }
            #[test]
            fn the_incline_rolls_and_slides_as_mechanics_says() {
                t::the_incline_rolls_and_slides_as_mechanics_says()
            }
            #[test]
            fn a_line_fit_recovers_a_line() {
                t::a_line_fit_recovers_a_line()
            }
            #[test]
            #[ignore = "a benchmark of the physics (about a minute in release): run by `coulomb validate`"]
            fn janssen_length_matches() {
                t::janssen_length_matches()
            }
            #[test]
            #[ignore = "a benchmark of the physics (about 10 minutes in release): run by `coulomb validate`"]
            fn beverloo_fit_is_in_range() {
                t::beverloo_fit_is_in_range()
            }
            #[test]
            #[ignore = "a benchmark of the physics (about 3 minutes in release): run by `coulomb validate`"]
            fn repose_angle_is_in_range() {
                t::repose_angle_is_in_range()
            }
        }
    }
    mod rigid {
        mod bench {
            use coulomb_granular::unit_tests::validation::rigid::bench as t;
            #[test]
            #[ignore = "benchmark: scripts/bench_rigid_pile.sh"]
            fn rigid_pile_benchmark() {
                t::rigid_pile_benchmark()
            }
        }
        mod impact_tests {
            use coulomb_granular::unit_tests::validation::rigid::impact_tests as t;
            #[test]
            fn small_wall_is_knocked_over_by_a_ball() {
                t::small_wall_is_knocked_over_by_a_ball()
            }
            #[test]
            #[ignore = "long (18 bricks, 120 steps): a `coulomb validate` check"]
            fn five_course_wall_collapses() {
                t::five_course_wall_collapses()
            }
        }
        mod report {
            use coulomb_granular::unit_tests::validation::rigid::report as t;
            #[test]
            #[ignore = "long (the 10-course wall and the 5-layer pyramid): run by `coulomb validate`"]
            fn print_rigid_checks() {
                t::print_rigid_checks()
            }
        }
        mod shape_tests {
            use coulomb_granular::unit_tests::validation::rigid::shape_tests as t;
            #[test]
            fn every_shape_comes_to_rest_on_a_plane_and_a_mesh() {
                t::every_shape_comes_to_rest_on_a_plane_and_a_mesh()
            }
        }
        mod stack_tests {
            use coulomb_granular::unit_tests::validation::rigid::stack_tests as t;
            #[test]
            fn tall_block_topples_and_cube_slides_on_an_incline() {
                t::tall_block_topples_and_cube_slides_on_an_incline()
            }
            #[test]
            fn small_wall_and_pyramid_stand() {
                t::small_wall_and_pyramid_stand()
            }
        }
        mod tests {
            use coulomb_granular::unit_tests::validation::rigid::tests as t;
            #[test]
            fn torque_free_top_keeps_momentum_and_energy() {
                t::torque_free_top_keeps_momentum_and_energy()
            }
            #[test]
            fn tennis_racket_flips() {
                t::tennis_racket_flips()
            }
            #[test]
            fn resting_box_carries_its_weight() {
                t::resting_box_carries_its_weight()
            }
            #[test]
            fn box_slides_down_an_incline() {
                t::box_slides_down_an_incline()
            }
            #[test]
            fn box_sticks_on_a_gentle_incline() {
                t::box_sticks_on_a_gentle_incline()
            }
        }
    }
}
