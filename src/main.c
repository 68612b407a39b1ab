static const char help[] =
    "kergs: Non-Smooth Contact Dynamics of dense, confined granular media (Moreau-Jean time stepping, NLGS).\n"
    "Usage: mpirun -n N kergs -options_file cases/X.opts [options]\n"
    "Every option of the scene, the solver, the output and the time loop is listed below; docs/ describes the files.\n\n";

#include <kergs/kergs.h>
#include <limits.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

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
  /* options under any prefix that PETSc reads when a preconditioner is first set up, inside the time loop, after the
     check: a factorization package's (-solver_mat_mumps_icntl_7) and those of inner solvers (-solver_sub_pc_type lu of
     block Jacobi or additive Schwarz, -solver_mg_levels_ksp_type of multigrid), and those of the Newton type's linear solver, which it sets
     up per step (-solver_ksp_rtol is read only once GMRES replaces the one-rank default) */
  static const char *packages[] = {"mat_mumps_", "mat_cholmod_", "mat_umfpack_", "mat_klu_",   "mat_superlu_",      "sub_",
                                   "mg_levels_", "mg_coarse_",   "solver_ksp_",  "solver_pc_", "solver_redundant_", NULL};
  for (PetscInt i = 0; prefixes[i]; i++) {
    size_t n = strlen(prefixes[i]);
    if (!strncmp(name, prefixes[i], n) && (prefixes[i][n - 1] == '_' || name[n] == '\0' || name[n] == '_')) return PETSC_TRUE;
  }
  for (PetscInt i = 0; packages[i]; i++)
    if (strstr(name, packages[i])) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* An option that nothing read is a typo or belongs to another program: refuse it instead of ignoring it. */
static PetscErrorCode CheckUnusedOptions(MPI_Comm comm, PetscBool fclib)
{
  PetscInt  n;
  char    **names, **values;
  PetscBool allow = PETSC_FALSE, bad = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(KergsOptionsCheckBool(comm, NULL, "-allow_unused_options"));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-allow_unused_options", &allow, NULL));
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  for (PetscInt i = 0; i < n; i++) {
    if (IsPetscOption(names[i])) continue;
    PetscCall(PetscPrintf(comm, "kergs: %s option -%s%s%s\n", fclib ? "an -fclib_input run does not use" : "unknown", names[i],
                          values[i] ? " " : "", values[i] ? values[i] : ""));
    bad = PETSC_TRUE;
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscCheck(!bad || allow || !fclib, comm, PETSC_ERR_USER_INPUT,
             "Option(s) listed above: an -fclib_input run solves one problem with the solver's options and writes -output; the options of "
             "a scene and its time loop (-steps, -checkpoint_*, -progress_*, ...) do not apply to it: remove them, or misspelled? "
             "(-allow_unused_options to accept them)");
  PetscCheck(!bad || allow, comm, PETSC_ERR_USER_INPUT,
             "Unknown option(s) listed above: misspelled? kergs -help lists every option (-allow_unused_options to accept them)");
  PetscFunctionReturn(0);
}

/* The options files (-options_file of the command line and those they include), copied as the walk finds them (one
   more than the stepper keeps, for its error to name): PETSc reads them into the options database and forgets their
   names, which the checks of the run's paths need (no output may replace an input). */
typedef struct {
  int  n;
  char path[9][PETSC_MAX_PATH_LEN];
} OptionsFiles;

static void CollectOptionsFile(const char path[], void *ctx)
{
  OptionsFiles *files = (OptionsFiles *)ctx;
  if (files->n < 9) snprintf(files->path[files->n++], PETSC_MAX_PATH_LEN, "%s", path);
}

/* The options files of the command line, walked again at each call (a malformed one is the options reader's error) */
static const OptionsFiles *GetOptionsFiles(int argc, char **argv)
{
  static OptionsFiles files;
  char                msg[256];

  files.n = 0;
  (void)KergsOptionsFilesWalk(argc, argv, CollectOptionsFile, &files, msg, sizeof(msg));
  return &files;
}

static PetscErrorCode AddOptionsFiles(KergsStepper stepper, int argc, char **argv)
{
  const OptionsFiles *files = GetOptionsFiles(argc, argv);

  PetscFunctionBeginUser;
  for (int i = 0; i < files->n; i++) PetscCall(KergsStepperAddInput(stepper, "-options_file", files->path[i]));
  PetscFunctionReturn(0);
}

/* A PETSc viewer opens its file when its option is read (-solver_monitor ascii:FILE truncates FILE), before the run's
   own path checks: the viewers' files are checked first against the inputs, the options files included. */
#define NAMED_INPUTS 3
static const char *NamedInputs[NAMED_INPUTS] = {"-sample_input", "-restart", "-fclib_input"};

/* The values of NamedInputs, read from the database's text: not marked as read, since KergsOptionsCheckValues looks
   for options given without their value among those not read yet. */
static PetscErrorCode TakeNamedInput(const char name[], const char value[], void *ctx)
{
  char(*given)[PETSC_MAX_PATH_LEN] = (char(*)[PETSC_MAX_PATH_LEN])ctx;

  PetscFunctionBeginUser;
  for (int k = 0; k < NAMED_INPUTS; k++)
    if (!strcmp(name, NamedInputs[k])) snprintf(given[k], PETSC_MAX_PATH_LEN, "%s", value);
  PetscFunctionReturn(0);
}

static PetscErrorCode CheckViewerFiles(int argc, char **argv)
{
  static char       given[NAMED_INPUTS][PETSC_MAX_PATH_LEN];
  KergsViewerFiles *vf;
  KergsFileRole     outputs[KERGS_MAX_VIEWER_FILES], inputs[NAMED_INPUTS + 9];
  PetscInt          nin = 0;
  char             *all;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&vf));
  PetscCall(KergsFileViewerFiles(vf));
  if (vf->n) { /* no viewer's file, nothing to check */
    const OptionsFiles *files = GetOptionsFiles(argc, argv);
    for (int i = 0; i < files->n; i++) inputs[nin++] = (KergsFileRole){"-options_file", files->path[i]};
    PetscCall(PetscOptionsGetAll(NULL, &all));
    PetscCall(KergsOptionsTextWalk(all, TakeNamedInput, given));
    PetscCall(PetscFree(all));
    for (int k = 0; k < NAMED_INPUTS; k++) inputs[nin++] = (KergsFileRole){NamedInputs[k], given[k]};
    for (PetscInt k = 0; k < vf->n; k++) outputs[k] = (KergsFileRole){vf->option[k], vf->path[k]};
    PetscCall(KergsFileCheckPaths(PETSC_COMM_WORLD, vf->n, outputs, nin, inputs, 0, NULL));
  }
  PetscCall(PetscFree(vf));
  PetscFunctionReturn(0);
}

/* -fclib_input FILE: one FCLib problem instead of a scene */
static PetscErrorCode RunFCLib(int argc, char **argv, KergsExitStatus *status)
{
  const OptionsFiles *files = GetOptionsFiles(argc, argv);
  KergsFCLibRun       run;
  KergsSolver         solver;

  PetscFunctionBeginUser;
  (void)KergsStepperCatchStopSignals(PETSC_FALSE); /* one solve, no time loop to stop cleanly: a signal ends it */
  PetscCall(KergsFCLibRunCreate(PETSC_COMM_WORLD, &run));
  for (int i = 0; i < files->n; i++) PetscCall(KergsFCLibRunAddInput(run, "-options_file", files->path[i]));
  PetscCall(KergsFCLibRunSetFromOptions(run));
  PetscCall(KergsFCLibRunGetSolver(run, &solver));
  PetscCall(CheckUnusedOptions(PETSC_COMM_WORLD, PETSC_TRUE));
  PetscCall(KergsSolverViewFromOptions(solver, "-solver_view"));
  PetscCall(KergsFCLibRunSolve(run, status));
  PetscCall(KergsFCLibRunDestroy(&run));
  PetscFunctionReturn(0);
}

/* Everything kergs -help lists: with -restart, the checkpointed run's options first; the run's objects, every solver
   type and the FCLib run (KergsOptionsCheckValues runs it with -help set). */
static PetscErrorCode ReadAllOptions(MPI_Comm comm, void *ctx)
{
  KergsStepper stepper;
  char         checkpoint[PETSC_MAX_PATH_LEN];
  PetscBool    restart;

  PetscFunctionBeginUser;
  (void)ctx;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-restart", checkpoint, sizeof(checkpoint), &restart));
  if (restart && checkpoint[0]) PetscCall(KergsCheckpointLoadOptions(comm, checkpoint));
  PetscCall(KergsStepperCreate(comm, &stepper));
  PetscCall(KergsStepperSetFromOptions(stepper));
  PetscCall(KergsSolverPrintHelpAllTypes(comm));
  PetscCall(KergsFCLibRunPrintHelp(comm));
  PetscCall(KergsStepperDestroy(&stepper));
  PetscFunctionReturn(0);
}

static PetscErrorCode Run(int argc, char **argv, KergsExitStatus *status)
{
  KergsStepper stepper;
  PetscBool    want_help = PETSC_FALSE, restart, fclib;
  char         checkpoint[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscOptionsHasHelp(NULL, &want_help));
  PetscCall(CheckViewerFiles(argc, argv));
  if (!want_help) PetscCall(KergsOptionsCheckValues(PETSC_COMM_WORLD, ReadAllOptions, NULL)); /* "-dt" alone is an error */
  PetscCall(PetscOptionsHasName(NULL, NULL, "-fclib_input", &fclib));
  if (fclib && !want_help) {
    PetscCall(RunFCLib(argc, argv, status));
    PetscFunctionReturn(0);
  }
  /* a restart: the checkpointed run's options enter the database before anything reads it (the command line wins) */
  PetscCall(PetscOptionsGetString(NULL, NULL, "-restart", checkpoint, sizeof(checkpoint), &restart));
  if (restart && !want_help) PetscCall(KergsCheckpointLoadOptions(PETSC_COMM_WORLD, checkpoint));
  PetscCall(KergsStepperCreate(PETSC_COMM_WORLD, &stepper));
  PetscCall(AddOptionsFiles(stepper, argc, argv));
  PetscCall(KergsStepperSetFromOptions(stepper));
  /* with -help, the options of every solver type, not only of the chosen one */
  if (want_help) {
    PetscCall(KergsSolverPrintHelpAllTypes(PETSC_COMM_WORLD));
    PetscCall(KergsFCLibRunPrintHelp(PETSC_COMM_WORLD));
  } else {
    PetscCall(CheckUnusedOptions(PETSC_COMM_WORLD, PETSC_FALSE));
    PetscCall(KergsStepperViewFromOptions(stepper));
    PetscCall(KergsStepperRun(stepper));
    PetscCall(KergsStepperGetExitStatus(stepper, status));
  }
  PetscCall(KergsStepperDestroy(&stepper));
  PetscFunctionReturn(0);
}

/* Exit status (docs/running.md, KergsExitStatus): 0 done; 1 an error (its message says what); 2 a blow-up; 3 done with
   steps that did not converge under -error_on_nonconvergence; 4 stopped by SIGTERM, SIGINT or SIGUSR1 (checkpoint
   written, files closed); 5 the contact solver diverged. */
int main(int argc, char **argv)
{
  KergsExitStatus status = KERGS_EXIT_DONE;
  PetscErrorCode  ierr;
  char          **args = argv;

  KergsReturnFreedMemory();      /* peak resident memory = peak of live data (base.h) */
  KergsFileAvoidLongPathAbort(); /* before MPI_Init: Open MPI's MPI-IO and paths of 241 characters or more */
  /* a batch system's stop signal may come at once: caught before MPI_Init, and again after it should MPI or PETSc
     have taken one (the time loop polls the flag before its first step) */
  (void)KergsStepperCatchStopSignals(PETSC_TRUE);
  {
    char msg[2 * PATH_MAX]; /* PETSc would recurse into a file that includes itself until the stack overflows */
    if (KergsOptionsFilesWalk(argc, argv, NULL, NULL, msg, sizeof(msg))) {
      const char *rank = getenv("OMPI_COMM_WORLD_RANK");
      if (!rank || !strcmp(rank, "0")) fprintf(stderr, "kergs: error: %s\n", msg);
      return KERGS_EXIT_ERROR;
    }
  }
  ierr = PetscInitialize(&argc, &argv, NULL, help);
  if (ierr) return KERGS_EXIT_ERROR;
  if (KergsStepperCatchStopSignals(PETSC_TRUE)) return KERGS_EXIT_ERROR;
  if (KergsPushErrorHandler()) return KERGS_EXIT_ERROR; /* a failed allocation says "out of memory" */
  ierr = Run(argc, args, &status);
  /* the run is over and its status known: a batch scheduler's warning signal (Slurm's --signal, SIGUSR1) arriving
     during the last clean-up must not turn it into a failure */
  if (!ierr) (void)signal(SIGUSR1, SIG_IGN);
  if (ierr) {
    /* the error was printed where it arose; every rank ends with the documented status, whatever rank failed (a rank
       waiting in a collective call is ended too) */
    MPI_Abort(PETSC_COMM_WORLD, KERGS_EXIT_ERROR);
    return KERGS_EXIT_ERROR;
  }
  (void)PetscPopErrorHandler(); /* KergsPushErrorHandler's, freed before PETSc counts its leaks */
  ierr = PetscFinalize();
  return ierr ? KERGS_EXIT_ERROR : (int)status;
}
