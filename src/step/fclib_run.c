/* kergs -fclib_input FILE: one FCLib problem (src/io/fclib_import.c) solved by the solver of the options instead of a
   time loop, with the statistics of a step in the results file and a summary line like the step lines
   (docs/solver.md, "Solving FCLib problems"). The problem's contacts are all active (an FCLib problem holds the law
   of every contact it lists) and start from r = 0, as Siconos's solvers do. The solver sees a contact set and
   operators built from the data (KergsContactsRestore, KergsOperatorsSetProblem) and an empty scene: the types that
   need the scene's H_f (the kernel-regularised ones) are refused. */
#include <kergs/private/stepperimpl.h>
#include <kergs/fclib.h>

struct _p_KergsFCLibRun {
  MPI_Comm          comm;
  char              path[PETSC_MAX_PATH_LEN];   /* -fclib_input */
  char              name[PETSC_MAX_PATH_LEN];   /* its base name without .h5 / .fclib.h5: the default results/<name>.h5 */
  char              solved[PETSC_MAX_PATH_LEN]; /* -fclib_output: the problem with the solution found, or empty */
  KergsInputFiles   inputs;                     /* the options files (KergsFCLibRunAddInput) */
  PetscBool         error_on_nonconvergence;
  PetscBool         start_solution; /* -fclib_start solution: start from the file's solution instead of r = 0 */
  KergsFCLibProblem problem;
  KergsScene        scene;
  KergsContacts     contacts;
  KergsOperators    ops;
  KergsSolver       solver;
  KergsResults      results;
};

PetscErrorCode KergsFCLibRunCreate(MPI_Comm comm, KergsFCLibRun *run)
{
  KergsFCLibRun r;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&r));
  r->comm = comm;
  PetscCall(KergsSceneCreate(comm, &r->scene));
  PetscCall(KergsContactsCreate(comm, &r->contacts));
  PetscCall(KergsOperatorsCreate(comm, &r->ops));
  PetscCall(KergsSolverCreate(comm, &r->solver));
  PetscCall(KergsResultsCreate(comm, &r->results));
  *run = r;
  PetscFunctionReturn(0);
}

/* results/<name>.h5 by default, name the file's base name without its extensions (.fclib.h5, .h5, .hdf5) */
static PetscErrorCode FCLibRunName(KergsFCLibRun r)
{
  const char *base  = strrchr(r->path, '/');
  const char *ext[] = {".fclib.h5", ".h5", ".hdf5"};

  PetscFunctionBeginUser;
  PetscCall(PetscStrncpy(r->name, base ? base + 1 : r->path, sizeof(r->name)));
  for (size_t k = 0; k < sizeof(ext) / sizeof(ext[0]); k++) {
    size_t n = strlen(r->name), e = strlen(ext[k]);
    if (n > e && !strcmp(r->name + n - e, ext[k])) {
      r->name[n - e] = 0;
      break;
    }
  }
  PetscFunctionReturn(0);
}

/* -fclib_input, -fclib_start, -fclib_output, -error_on_nonconvergence */
static PetscErrorCode FCLibRunOptions(KergsFCLibRun r, PetscBool *set)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(r->comm, NULL, "FCLib problem (instead of a scene)", NULL);
  PetscCall(PetscOptionsString("-fclib_input",
                               "Solve this 2D FCLib problem (local, or global with a diagonal M) instead of running a scene",
                               "KergsFCLibRead", r->path, r->path, sizeof(r->path), set));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-error_on_nonconvergence", "Exit with status 3 if the solve did not converge", "",
                             r->error_on_nonconvergence, &r->error_on_nonconvergence, NULL));
  {
    const char *starts[] = {"zero", "solution"};
    PetscInt    start    = r->start_solution ? 1 : 0;
    PetscCall(PetscOptionsEList("-fclib_start",
                                "Initial impulses: zero, or the solution stored in the file (a check of the import: it is a solution)", "",
                                starts, 2, starts[start], &start, NULL));
    r->start_solution = (PetscBool)(start == 1);
  }
  PetscCall(PetscOptionsString("-fclib_output",
                               "With -fclib_input: write the problem again with the impulses found as its solution (local form, FCLib)",
                               "KergsFCLibExportSolved", r->solved, r->solved, sizeof(r->solved), NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRunPrintHelp(MPI_Comm comm)
{
  KergsFCLibRun r;
  PetscBool     set;

  PetscFunctionBeginUser;
  PetscCall(KergsFCLibRunCreate(comm, &r));
  PetscCall(FCLibRunOptions(r, &set));
  PetscCall(KergsFCLibRunDestroy(&r));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRunAddInput(KergsFCLibRun r, const char option[], const char path[])
{
  PetscFunctionBeginUser;
  PetscCall(KergsInputFilesAdd(r->comm, &r->inputs, option, path));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRunSetFromOptions(KergsFCLibRun r)
{
  PetscBool       set, needs_H;
  KergsSolverType type;
  const char     *out;
  PetscBool       enabled;
  KergsFileRole   outputs[2], inputs[1 + KERGS_STEPPER_MAXINPUTS];

  PetscFunctionBeginUser;
  PetscCall(FCLibRunOptions(r, &set));
  PetscCheck(set && r->path[0], r->comm, PETSC_ERR_ARG_WRONG, "Option -fclib_input needs a file name");
  PetscCall(FCLibRunName(r));
  PetscCall(KergsSolverSetFromOptions(r->solver));
  PetscCall(KergsSolverGetType(r->solver, &type));
  PetscCall(KergsSolverNeedsH(r->solver, &needs_H));
  PetscCheck(
      !needs_H, r->comm, PETSC_ERR_SUP,
      "-solver_type %s needs the scene's H_f here (the kernel projector of nlkergs, nlgsjac and of newton's -solver_prox kernel, the "
      "predictors read the bodies): an FCLib problem holds W (or M and H without the bodies' geometry); solve it with -solver_type nlgs "
      "or newton (-solver_prox identity, the default)",
      type);
  PetscCall(KergsResultsSetSceneName(r->results, r->name));
  {
    PetscBool every, quiet;
    PetscCall(PetscOptionsHasName(NULL, NULL, "-output_every", &every));
    PetscCheck(!every, r->comm, PETSC_ERR_ARG_WRONG,
               "-output_every: an -fclib_input run writes one /stats row and no snapshot (there are no bodies); remove it");
    PetscCall(KergsOptionsCheckBool(r->comm, NULL, "-quiet"));
    PetscCall(PetscOptionsHasName(NULL, NULL, "-quiet", &quiet)); /* accepted: no step lines to silence, the summary stays */
  }
  PetscCall(KergsResultsSetFromOptions(r->results));
  PetscCall(KergsResultsGetPath(r->results, &out, &enabled));
  outputs[0] = (KergsFileRole){"-output", enabled ? out : NULL};
  outputs[1] = (KergsFileRole){"-fclib_output", r->solved[0] ? r->solved : NULL};
  inputs[0]  = (KergsFileRole){"-fclib_input", r->path};
  for (PetscInt k = 0; k < r->inputs.n; k++) inputs[1 + k] = (KergsFileRole){r->inputs.option[k], r->inputs.path[k]};
  PetscCall(KergsFileCheckPaths(r->comm, 2, outputs, 1 + r->inputs.n, inputs, 0, NULL));
  PetscCall(KergsFCLibRead(r->comm, r->path, &r->problem));
  PetscCheck(!r->start_solution || r->problem.r_ref, r->comm, PETSC_ERR_ARG_WRONG, "-fclib_start solution: %s holds no solution", r->path);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRunGetSolver(KergsFCLibRun r, KergsSolver *solver)
{
  PetscFunctionBeginUser;
  *solver = r->solver;
  PetscFunctionReturn(0);
}

/* The contacts of the problem, rank after rank: all active (gap 0 under the scene's default gap rule), zero impulse. */
static PetscErrorCode FCLibRunSetUp(KergsFCLibRun r, PetscInt *start, PetscInt *nlocal)
{
  const KergsFCLibProblem *p = &r->problem;
  PetscInt                 N = p->ncontacts;
  KergsContact            *c;

  PetscFunctionBeginUser;
  *nlocal = PETSC_DECIDE;
  PetscCall(PetscSplitOwnership(r->comm, nlocal, &N));
  *start = 0;
  PetscCallMPI(MPI_Exscan(nlocal, start, 1, MPIU_INT, MPI_SUM, r->comm));
  {
    PetscMPIInt rank;
    PetscCallMPI(MPI_Comm_rank(r->comm, &rank));
    if (rank == 0) *start = 0;
  }
  PetscCall(PetscCalloc1(PetscMax(*nlocal, 1), &c));
  for (PetscInt k = 0; k < *nlocal; k++) {
    c[k].kind = KERGS_CONTACT_DISK_WALL; /* bodies do not exist here: a key in contact order only */
    c[k].a    = k;
    c[k].b    = 0;
    c[k].idb  = 0;
    c[k].gap  = 0.0;
    c[k].mu   = p->mu[*start + k];
    for (PetscInt j = 0; j < 2; j++) c[k].r[j] = r->start_solution ? p->r_ref[2 * (*start + k) + j] : 0.0;
  }
  PetscCall(KergsContactsRestore(r->contacts, *nlocal, c));
  PetscCall(PetscFree(c));
  PetscCall(KergsOperatorsSetProblem(r->ops, *nlocal, 2, p->rowptr, p->colind, p->val, p->q));
  PetscCall(KergsOperatorsGetImpulses(r->ops, r->contacts));
  PetscFunctionReturn(0);
}

/* The solution against the one stored in the file: relative differences of the impulses r and of the velocities
   u = W r + q (u is unique where r need not be: W is singular in confined packings), -1 when the file holds none. */
static PetscErrorCode FCLibRunCompare(KergsFCLibRun r, PetscInt start, PetscReal *dr, PetscReal *du)
{
  Vec          rv, vd, rref, u, uref;
  Mat          W;
  PetscScalar *a;
  PetscInt     n;
  PetscReal    nref, nq;

  PetscFunctionBeginUser;
  *dr = *du = -1.0;
  if (!r->problem.r_ref) PetscFunctionReturn(0);
  PetscCall(KergsOperatorsGetContactVectors(r->ops, &rv, NULL, &vd));
  PetscCall(KergsOperatorsGetW(r->ops, &W, NULL));
  PetscCall(VecDuplicate(rv, &rref));
  PetscCall(VecDuplicate(rv, &u));
  PetscCall(VecDuplicate(rv, &uref));
  PetscCall(VecGetLocalSize(rref, &n));
  PetscCall(VecGetArray(rref, &a));
  for (PetscInt i = 0; i < n; i++) a[i] = r->problem.r_ref[2 * start + i];
  PetscCall(VecRestoreArray(rref, &a));
  PetscCall(MatMultAdd(W, rv, vd, u));
  PetscCall(MatMultAdd(W, rref, vd, uref));
  PetscCall(VecNorm(rref, NORM_2, &nref));
  PetscCall(VecNorm(vd, NORM_2, &nq));
  PetscCall(VecAYPX(rref, -1.0, rv));
  PetscCall(VecAYPX(uref, -1.0, u));
  PetscCall(VecNorm(rref, NORM_2, dr));
  PetscCall(VecNorm(uref, NORM_2, du));
  if (nref > 0) *dr /= nref;
  if (nq > 0) *du /= nq;
  PetscCall(VecDestroy(&rref));
  PetscCall(VecDestroy(&u));
  PetscCall(VecDestroy(&uref));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRunSolve(KergsFCLibRun r, KergsExitStatus *status)
{
  KergsSolveStats ss;
  KergsSolverType type;
  PetscInt        start, nlocal;
  PetscReal       dr, du, nnz_Hf, nnz_W, peak;
  const char     *out;
  PetscBool       enabled;

  PetscFunctionBeginUser;
  PetscCall(FCLibRunSetUp(r, &start, &nlocal));
  PetscCall(KergsResultsOpen(r->results));
  PetscCall(KergsSolverSolve(r->solver, r->scene, r->contacts, r->ops, &ss));
  PetscCall(KergsOperatorsSetImpulses(r->ops, r->contacts));
  PetscCall(FCLibRunCompare(r, start, &dr, &du));
  PetscCall(KergsSolverGetType(r->solver, &type));
  PetscCall(KergsOperatorsGetNonzeros(r->ops, &nnz_Hf, &nnz_W));
  PetscCall(KergsStepperPeakMemory(r->comm, &peak));
  PetscCall(KergsResultsRecordText(r->results, "solver_type", type));
  PetscCall(KergsResultsRecordText(r->results, "fclib_input", r->path));
  PetscCall(KergsResultsRecordText(r->results, "fclib_problem", r->problem.global ? "global" : "local"));
  PetscCall(KergsResultsRecord(r->results, "step", 1.0));
  PetscCall(KergsResultsRecord(r->results, "contacts", (PetscReal)r->problem.ncontacts));
  PetscCall(KergsResultsRecord(r->results, "active", (PetscReal)r->problem.ncontacts));
  PetscCall(KergsResultsRecord(r->results, "nnz_W", nnz_W));
  PetscCall(KergsResultsRecord(r->results, "peak_memory", peak));
  PetscCall(KergsStepperRecordSolve(r->results, &ss));
  if (dr >= 0) {
    PetscCall(KergsResultsRecord(r->results, "reference_impulse_difference", dr));
    PetscCall(KergsResultsRecord(r->results, "reference_velocity_difference", du));
  }
  PetscCall(KergsResultsEndStep(r->results));
  PetscCall(KergsResultsSetEnd(r->results, "done"));
  PetscCall(KergsResultsClose(r->results));
  PetscCall(PetscPrintf(
      r->comm, "fclib %s contacts %6" PetscInt_FMT " iterations %4" PetscInt_FMT "%s residual %8.2e velocity error %8.2e solve %.3g s\n",
      r->name, r->problem.ncontacts, ss.iterations, ss.reason > 0 ? "  " : " !", (double)ss.residual, (double)ss.velocity_error,
      (double)ss.seconds));
  if (dr >= 0)
    PetscCall(PetscPrintf(r->comm,
                          "kergs: against the file's solution: impulses differ by %.3g, velocities u = W r + q by %.3g (relative)\n",
                          (double)dr, (double)du));
  PetscCall(KergsResultsGetPath(r->results, &out, &enabled));
  if (enabled) PetscCall(PetscPrintf(r->comm, "kergs: results in %s\n", out));
  if (r->solved[0]) { /* after the results file is closed: a failed write loses nothing of the solve */
    PetscCall(KergsFCLibExportSolved(r->contacts, r->ops, r->path, r->solved));
    PetscCall(PetscPrintf(r->comm, "kergs: the problem%s in %s\n", r->problem.ncontacts ? " with its solution" : " (empty: no solution)",
                          r->solved));
  }
  *status = (ss.reason > 0 || !r->error_on_nonconvergence) ? KERGS_EXIT_DONE : KERGS_EXIT_NOT_CONVERGED;
  PetscCall(PetscPrintf(r->comm, "kergs: %s, exit status %d\n", ss.reason > 0 ? "done" : "done, not converged", (int)*status));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRunDestroy(KergsFCLibRun *r)
{
  PetscFunctionBeginUser;
  if (!*r) PetscFunctionReturn(0);
  PetscCall(KergsFCLibProblemFree(&(*r)->problem));
  PetscCall(KergsResultsDestroy(&(*r)->results));
  PetscCall(KergsSolverDestroy(&(*r)->solver));
  PetscCall(KergsOperatorsDestroy(&(*r)->ops));
  PetscCall(KergsContactsDestroy(&(*r)->contacts));
  PetscCall(KergsSceneDestroy(&(*r)->scene));
  PetscCall(PetscFree(*r));
  PetscFunctionReturn(0);
}
