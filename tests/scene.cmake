# Scene: options, generators, walls, errors (tests/test_scene.c); the same checks on 1 and 2 ranks,
# where the distributed scene, gathered in global-index order, must be identical on every rank.
kergs_test(NAME scene_1 SOURCE test_scene.c NPROCS 1 FAIL_REGEX "FAILED")
kergs_test(NAME scene_2 SOURCE test_scene.c NPROCS 2 FAIL_REGEX "FAILED")
# Every scene option is listed by -help on its own help line, wall options under their wall_<name>_ prefix; then the
# scene's view.
kergs_test(NAME scene_help SOURCE test_scene.c NPROCS 1
           ARGS -from_command_line -help -box 0,0,1,1 -walls piston -wall_piston_a 1,1 -wall_piston_b 0,1 -disks_x 0.5,0.5 -disks_radius 0.1
           EXPECT_OUTPUT -scene_name -gravity -dt -steps -theta -gap_rule -alert -materials -material_density -friction
                       -friction_pairs -box -box_open_top -walls -wall_box_bottom_a -wall_box_left_force -wall_piston_a
                       -wall_piston_b -wall_piston_type -wall_piston_infinite -wall_piston_material -wall_piston_velocity
                       -wall_piston_program -wall_piston_mass -wall_piston_force -wall_piston_pressure -wall_piston_guided -disks_source -disks_material -disks_x
                       -disks_radius -disks_velocity -lattice_type -lattice_n -lattice_radius -lattice_origin -lattice_spacing
                       -random_n -random_box -random_radius -random_seed -sample_input "Scene unnamed: 1 disks")
