# Batch use (docs/running.md): counts that do not fit in the build's 32-bit integers are refused, not wrapped.
kergs_bad_input(steps_overflow "Option .steps: 10000000000 is out of the range" -options_file cases/confine5.opts -steps 10000000000)
kergs_bad_input(lattice_overflow "lattice_n 65536,65537 asks for 4295032832 disks"
                -options_file cases/confine5.opts -disks_source lattice -lattice_n 65536,65537 -lattice_radius 0.1)
kergs_bad_input(solver_count_overflow "Option .solver_max_it: 3000000000 is out of the range" -options_file cases/confine5.opts -solver_max_it 3000000000)
