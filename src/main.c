static const char help[] =
    "kergs: Non-Smooth Contact Dynamics of dense, confined granular media (Moreau-Jean time stepping, NLGS).\n"
    "Usage: mpirun -n N kergs -options_file cases/X.opts [options]\n"
    "Every option of the scene, the solver, the output and the time loop is listed below; docs/ describes the files.\n\n";

#include <kergs/kergs.h>

/* Options that PETSc itself reads late (at finalize) or that tune PETSc, and so may legitimately look unused. */
static PetscBool IsPetscOption(const char *name)
{
  static const char *prefixes[] = {"log",
                                   "malloc",
                                   "options_",
                                   "help",
                                   "info",
                                   "on_error",
                                   "objects_",
                                   "history",
                                   "memory",
                                   "fp_trap",
                                   "check_pointer",
                                   "no_signal",
                                   "viewer",
                                   "skip_petscrc",
                                   "mat_mumps",
                                   "mat_",
                                   "ksp_",
                                   "pc_",
                                   "mpi",
                                   "debugger",
                                   "start_in_debugger",
                                   "stop_for_debugger",
                                   "nox",
                                   "display",
                                   "petsc",
                                   "version",
                                   "use_gpu",
                                   "device",
                                   NULL};
  /* a factorization package's options under any prefix (-solver_mat_mumps_icntl_7): read when the first matrix is
     factored, inside the time loop, after the check */
  static const char *packages[] = {"mat_mumps_", "mat_cholmod_", "mat_umfpack_", "mat_klu_", "mat_superlu_", NULL};
  for (PetscInt i = 0; prefixes[i]; i++) {
    size_t n = strlen(prefixes[i]);
    if (!strncmp(name, prefixes[i], n) && (prefixes[i][n - 1] == '_' || name[n] == '\0' || name[n] == '_')) return PETSC_TRUE;
  }
  for (PetscInt i = 0; packages[i]; i++)
    if (strstr(name, packages[i])) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* An option that nothing read is a typo or belongs to another program: refuse it instead of ignoring it. */
static PetscErrorCode CheckUnusedOptions(MPI_Comm comm)
{
  PetscInt  n;
  char    **names, **values;
  PetscBool allow = PETSC_FALSE, bad = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-allow_unused_options", &allow, NULL));
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  for (PetscInt i = 0; i < n; i++) {
    if (IsPetscOption(names[i])) continue;
    PetscCall(PetscPrintf(comm, "kergs: unknown option -%s%s%s\n", names[i], values[i] ? " " : "", values[i] ? values[i] : ""));
    bad = PETSC_TRUE;
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscCheck(!bad || allow, comm, PETSC_ERR_USER_INPUT,
             "Unknown option(s) listed above: misspelled? kergs -help lists every option (-allow_unused_options to accept them)");
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KergsStepper stepper;
  KergsScene   scene;
  KergsSolver  solver;
  PetscBool    want_help = PETSC_FALSE;

  KergsReturnFreedMemory(); /* peak resident memory = peak of live data (base.h) */
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(PetscOptionsHasHelp(NULL, &want_help));
  PetscCall(KergsStepperCreate(PETSC_COMM_WORLD, &stepper));
  PetscCall(KergsStepperSetFromOptions(stepper));
  PetscCall(KergsStepperGetScene(stepper, &scene));
  PetscCall(KergsStepperGetSolver(stepper, &solver));
  /* with -help, the options of every solver type, not only of the chosen one */
  if (want_help)
    PetscCall(KergsSolverPrintHelpAllTypes(PETSC_COMM_WORLD));
  else {
    PetscCall(CheckUnusedOptions(PETSC_COMM_WORLD));
    PetscCall(KergsSceneView(scene, PETSC_VIEWER_STDOUT_WORLD));
    PetscCall(KergsSolverView(solver, PETSC_VIEWER_STDOUT_WORLD));
    PetscCall(KergsStepperRun(stepper));
  }
  PetscCall(KergsStepperDestroy(&stepper));
  PetscCall(PetscFinalize());
  return 0;
}
