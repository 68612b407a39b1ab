# The quick biaxial workflow: cases/compact_small.opts compacts 300 area-law disks under four pressure walls until at
# rest, cases/biaxial_small.opts shears that sample at constant sigma3, each also at another friction (120 grains
# compacted at mu = 0 and 0.5; the shear at mu = 0), two 1-rank runs at a time; tests/check_biaxial.py checks the
# physics: packing, Rothenburg-Bathurst, contacts' stress against the walls', frictionless residual strength, and that
# the sample mirrored into 2 x 3 tiles by scripts/tile_sample.py stays at rest on 2 ranks.
kergs_python_check(biaxial_small check_biaxial.py PROCESSORS 2 TIMEOUT 400 LABELS step)

# Bad input for the biaxial test. A driven wall that shears the sample at an inertial number above 0.1 gets a warning
# at the start (not an error: the run goes on and exits 0) naming the wall, I and the formula's terms, printed by rank 0
# only. biaxial_small's top wall at 2 m/s over H0 = 0.527 m: eps_dot = 3.79 /s, I = 0.119.
add_test(NAME biaxial_inertial_warning
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh
                 "kergs: warning: wall box_top shears the sample at the inertial number I = eps_dot d sqrt\\(rho / sigma3\\) = 0\\.119, above 0\\.1 .*eps_dot = 2\\.? m/s / 0\\.527.* m = 3\\.79.* /s .* d = 0\\.0312.* m .* rho = 1\\.? kg/m\\^2, sigma3 = 1\\.? N/m"
                 "kergs: done, exit status 0" --
                 ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} 2 ${MPIEXEC_PREFLAGS} $<TARGET_FILE:kergs_exe> ${MPIEXEC_POSTFLAGS}
                 -options_file cases/biaxial_small.opts -wall_box_top_velocity 0,-2 -steps 0 -output_none
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(biaxial_inertial_warning PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 60 LABELS bad_input)
# A program is judged by the largest speed it reaches, not by its first piece: biaxial_small's top wall given a program
# that starts at 1 mm/s and reaches 2 m/s at t = 0.01 s gets the same warning as the constant 2 m/s above.
file(READ ${CMAKE_SOURCE_DIR}/cases/biaxial_small.opts biaxial_small_opts)
string(REGEX REPLACE "\n-wall_box_top_velocity[^\n]*" "" biaxial_small_opts "${biaxial_small_opts}")
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/biaxial_small_program.opts "${biaxial_small_opts}")
add_test(NAME biaxial_inertial_warning_program
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh
                 "kergs: warning: wall box_top shears the sample at the inertial number I = eps_dot d sqrt\\(rho / sigma3\\) = 0\\.119, above 0\\.1"
                 "kergs: done, exit status 0" --
                 ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} 1 ${MPIEXEC_PREFLAGS} $<TARGET_FILE:kergs_exe> ${MPIEXEC_POSTFLAGS}
                 -options_file ${CMAKE_CURRENT_BINARY_DIR}/biaxial_small_program.opts -wall_box_top_program 0,0,-0.001,0.01,0,-2
                 -steps 0 -output_none
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(biaxial_inertial_warning_program PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60 LABELS bad_input)
# On the sample's scale the top wall's speed against sqrt(sigma3 / rho) (I H / d): at 0.5 m/s biaxial_small's I is 0.03,
# below the first warning, but the wall moves at 0.5 sqrt(sigma3 / rho) over 17 diameters: the second warning.
add_test(NAME biaxial_sample_speed_warning
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh
                 "kergs: warning: wall box_top moves at 0\\.5 sqrt\\(sigma3 / rho\\) \\(= I H / d, the sample 17 mean diameters across\\), above 0\\.3: the sample's own inertia rho v\\^2 = 0\\.25 sigma3 .*whatever I = 0\\.0296"
                 "kergs: done, exit status 0" --
                 ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} 2 ${MPIEXEC_PREFLAGS} $<TARGET_FILE:kergs_exe> ${MPIEXEC_POSTFLAGS}
                 -options_file cases/biaxial_small.opts -wall_box_top_velocity 0,-0.5 -steps 0 -output_none
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(biaxial_sample_speed_warning PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 60 LABELS bad_input)

# scripts/tile_sample.py refuses, before writing anything: fewer than two tiles, an input that is not HDF5, a sample
# without the box it was compacted in (cases/deposit500.h5, a deposit under gravity), a box its grains do not reach
# (seams that would not touch), and its input as its output (on a copy, left unchanged: cmp). Its tiling is checked
# in biaxial_small (item 8).
set(TILE_SAMPLE /usr/bin/python3 ${CMAKE_SOURCE_DIR}/scripts/tile_sample.py)
foreach(case "one_tile|at least two tiles|cases/compact_small.h5;${CMAKE_CURRENT_BINARY_DIR}/tile_one.h5;--tiles;1,1"
             "bad_tiles|--tiles '2,x': expected two positive integers|cases/compact_small.h5;${CMAKE_CURRENT_BINARY_DIR}/tile_bad.h5;--tiles;2,x"
             "not_hdf5|cases/confine500.opts: not a readable HDF5 file|cases/confine500.opts;${CMAKE_CURRENT_BINARY_DIR}/tile_opts.h5;--tiles;2,2"
             "no_box|cases/deposit500.h5: no /sample/box|cases/deposit500.h5;${CMAKE_CURRENT_BINARY_DIR}/tile_nobox.h5;--tiles;2,2")
  string(REPLACE "|" ";" parts "${case}")
  list(GET parts 0 name)
  list(GET parts 1 regex)
  list(SUBLIST parts 2 -1 args)
  add_test(NAME tile_sample_${name} COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh "${regex}" ${TILE_SAMPLE} ${args}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(tile_sample_${name} PROPERTIES TIMEOUT 30 LABELS bad_input)
endforeach()
add_test(NAME tile_sample_onto_input
         COMMAND sh -c "cp cases/compact_small.h5 \"$0/tile_self.h5\" && \"$1\" \"is the input; write the tiling elsewhere\" /usr/bin/python3 scripts/tile_sample.py \"$0/tile_self.h5\" \"$0/tile_self.h5\" --tiles 2,2 && cmp cases/compact_small.h5 \"$0/tile_self.h5\""
                 ${CMAKE_CURRENT_BINARY_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(tile_sample_onto_input PROPERTIES TIMEOUT 30 LABELS bad_input)
add_test(NAME tile_sample_box_off
         COMMAND sh -c "cp cases/compact_small.h5 \"$0/tile_off.h5\" && /usr/bin/python3 -c \"import h5py; b = h5py.File('$0/tile_off.h5', 'r+')['sample/box']; v = b[()]; v[0, 2] += 0.05; b[...] = v\" && exec \"$1\" \"stand 0.05 m off the box's right side\" /usr/bin/python3 scripts/tile_sample.py \"$0/tile_off.h5\" \"$0/tile_off_out.h5\" --tiles 2,2"
                 ${CMAKE_CURRENT_BINARY_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(tile_sample_box_off PROPERTIES TIMEOUT 30 LABELS bad_input)
# A sample whose grains carry tangential forces on the walls (wall friction) cannot be mirrored into equilibrium: the
# seams would hold them without. cases/compact_10k.h5 records its contact forces; one wall contact is given friction.
add_test(NAME tile_sample_wall_friction
         COMMAND sh -c "cp cases/compact_10k.h5 \"$0/tile_friction.h5\" && /usr/bin/python3 -c \"import h5py, numpy as np; c = h5py.File('$0/tile_friction.h5', 'r+')['sample/contacts']; f = c['force'][()]; f[np.flatnonzero(c['kind'][()] == 1)[0], 1] = 0.01; c['force'][...] = f\" && exec \"$1\" \"carry tangential forces on the box walls\" /usr/bin/python3 scripts/tile_sample.py \"$0/tile_friction.h5\" \"$0/tile_friction_out.h5\" --tiles 2,2"
                 ${CMAKE_CURRENT_BINARY_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(tile_sample_wall_friction PROPERTIES TIMEOUT 30 LABELS bad_input)

# A refused sample: test `name` copies `source` to <build>/tests/<name>.h5, edits it with Python (`edit`, h5py's file
# open as f), runs kergs on `nprocs` ranks with it as -sample_input and the options that follow, and expects the
# error `regex`.
function(kergs_edited_sample name source edit regex nprocs)
  if(nprocs GREATER 1)
    set(run ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${nprocs} ${MPIEXEC_PREFLAGS} $<TARGET_FILE:kergs_exe> ${MPIEXEC_POSTFLAGS})
  else()
    set(run $<TARGET_FILE:kergs_exe>)
  endif()
  add_test(NAME ${name}
           COMMAND sh -c "cp ${source} \"$0/${name}.h5\" && /usr/bin/python3 -c \"import h5py, numpy as np; f = h5py.File('$0/${name}.h5', 'r+'); ${edit}\" && script=\"$1\" regex=\"$2\" && shift 2 && exec \"$script\" \"$regex\" \"$@\" -sample_input \"$0/${name}.h5\" -output \"$0/${name}_out.h5\""
                   ${CMAKE_CURRENT_BINARY_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh "${regex}" ${run} ${ARGN}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(${name} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS ${nprocs} TIMEOUT 60 LABELS bad_input)
endfunction()

# A sample's contact forces (/sample/contacts, the first step's warm start) are checked before the run writes anything:
# a NaN force, a contact of a grain the sample does not hold and a pair given twice are refused, naming the file. The
# forces (rows a_id, kind, b_id, normal force) are added to a copy of cases/compact_small.h5, which records none.
# The NaN is refused while the file is open: on 2 ranks it must exit at once (before errors were held until the file
# closed, PETSc kept rank 1 asleep for 10 s while rank 0 closed the file; the time limit below fails that).
foreach(case "nan|dataset /sample/contacts/force holds a value that is not finite .entry 0, block 0.|(0, 0, 1, float('nan'))|2"
             "unknown_grain|1 of its 1 contacts belong to no grain of the sample|(10**6, 0, 10**6 + 1, 1.0)|2"
             "repeated|1 of its contacts repeat a pair given before|(0, 0, 1, 1.0), (0, 0, 1, 2.0)|2")
  string(REPLACE "|" ";" parts "${case}")
  list(GET parts 0 name)
  list(GET parts 1 regex)
  list(GET parts 2 row)
  list(GET parts 3 nprocs)
  kergs_edited_sample(sample_contacts_${name} cases/compact_small.h5
                      "g = f['sample'].create_group('contacts'); t = np.array([${row}], dtype=float); g.attrs['ncontacts'] = np.int32(len(t)); g.attrs['walls'] = np.bytes_('box_bottom,box_right,box_top,box_left'); [g.create_dataset(n, data=t[:, j]) for j, n in enumerate(('a_id', 'kind', 'b_id'))]; g.create_dataset('force', data=np.column_stack([t[:, 3], 0 * t[:, 3]]))"
                      "[Ff]ile .*sample_contacts_${name}\\.h5: ${regex}" ${nprocs} -options_file cases/biaxial_small.opts -steps 1)
endforeach()
set_tests_properties(sample_contacts_nan PROPERTIES TIMEOUT 9)
# An attribute that is an array where one value is expected crashed PETSc's attribute reader (a segmentation fault with
# ncontacts as 1,000 integers): the file is now probed before the viewer reads it.
kergs_edited_sample(sample_contacts_ncontacts_array cases/compact_10k.h5 "f['sample/contacts'].attrs['ncontacts'] = np.arange(1000)"
                    "Sample file .*sample_contacts_ncontacts_array\\.h5: attribute ncontacts of /sample/contacts is not a single integer" 2
                    -options_file cases/biaxial_1m.opts -steps 1)
# A corrupt sample whose damage HDF5 itself reports ("Error in HDF5 call H5Lexists() Status -1", naming no file): the
# message names the file. Eight bytes of the /sample group's object header overwritten (its address from h5py, so that
# the damage stays in that header whatever the layout of cases/compact_small.h5).
kergs_edited_sample(sample_flipped cases/compact_small.h5 "a = h5py.h5o.get_info(f['sample'].id).addr; f.close(); b = open('$0/sample_flipped.h5', 'r+b'); b.seek(a); b.write(bytes([255] * 8)); b.close()"
                    "Sample file .*sample_flipped\\.h5: Error in HDF5 call" 2 -options_file cases/biaxial_small.opts -steps 1)
# A sample too large for the memory, read while its file is open (where errors are held until it is closed): the
# failed allocation is not held, it is reported as one and ends the run. Its datasets are declared for 200 million disks but not written, and a
# 3 GB address-space limit refuses the 3.2 GB of a coordinate vector without touching the machine's memory.
add_test(NAME sample_out_of_memory
         COMMAND sh -c "cp cases/compact_small.h5 \"$0/sample_oom.h5\" && /usr/bin/python3 -c \"import h5py, numpy as np; g = h5py.File('$0/sample_oom.h5', 'r+')['sample']; N = 200000000; [(lambda k, d: (g.__delitem__(k), g.create_dataset(k, shape=(N,) + d.shape[1:], dtype=d.dtype)))(k, g[k]) for k in list(g.keys()) if k != 'box' and isinstance(g[k], h5py.Dataset)]; g.attrs['ndisks'] = np.int32(N)\" && ulimit -v 3000000 && exec \"$1\" \"out of memory: an allocation in [A-Za-z_]+ failed\" \"$2\" -options_file cases/biaxial_small.opts -sample_input \"$0/sample_oom.h5\" -output_none"
                 ${CMAKE_CURRENT_BINARY_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh $<TARGET_FILE:kergs_exe>
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(sample_out_of_memory PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60 LABELS bad_input)
# A sample file is checked for what it must be before its grains are read: its format (root attribute kergs_format),
# its dimension, at least one grain. Each is an edited copy of cases/compact_small.h5, refused naming the file.
kergs_edited_sample(sample_bad_format cases/compact_small.h5 "del f.attrs['kergs_format']"
                    "File .*sample_bad_format\\.h5 is not a kergs sample" 1 -options_file cases/biaxial_small.opts -steps 1)
kergs_edited_sample(sample_bad_dim cases/compact_small.h5 "f['sample'].attrs['dim'] = np.int32(3)"
                    "Sample file .*sample_bad_dim\\.h5 is of dimension 3" 1 -options_file cases/biaxial_small.opts -steps 1)
kergs_edited_sample(sample_bad_empty cases/compact_small.h5 "f['sample'].attrs['ndisks'] = np.int32(0)"
                    "Sample file .*sample_bad_empty\\.h5: ndisks = 0: a sample holds at least one grain" 1
                    -options_file cases/biaxial_small.opts -steps 1)
