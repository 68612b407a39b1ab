/* Helpers shared by the test programs: the checks, a stepper configured only by given options, a recorded statistic by
   name, a per-disk field gathered by grain id, the natural residual of a step recomputed independently of the library.

   Assertion rule, for every program under tests/:
   - A property under test is asserted with Check() (or CheckAll(), Checkf() below): one line per check, "ok  " or
     "FAIL" with what was got and what was wanted. A failure is counted and the program goes on, so that one run
     reports every broken property; Finish() prints "PASSED"/"FAILED" with the count and gives the exit code.
   - PetscCheck() is kept only for set-up failures that are not the property under test (a file the test cannot
     write, a library it cannot load, an object the test itself built inconsistently): the program aborts there.
   - When a failed check makes what follows meaningless or unsafe (an index out of range, a missing object), the
     test function returns after the Check(), it does not turn the check into a PetscCheck().
   - Check() and Checkf() are local: on several ranks their ok, got and want must already agree on every rank
     (reduce first; rank 0 prints). CheckAll() and CheckTrue() (a yes/no property) are collective and reduce ok
     themselves (logical and over comm).
   No local Expect()-style macros: one style, one line format, one exit code. */
#ifndef KERGS_TESTING_H
#define KERGS_TESTING_H

#include "internals.h"
#include <stdarg.h>

static PetscInt nfail = 0;

/* Print one line per check ("ok" or "FAIL", with what was got and wanted) and count the failures. Local: ok, got and
   want must agree on every rank (rank 0 of PETSC_COMM_WORLD prints). */
static inline PetscErrorCode Check(PetscBool ok, const char *what, PetscReal got, PetscReal want)
{
  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s %-72s got %.10g want %.10g\n", ok ? "ok  " : "FAIL", what, (double)got, (double)want));
  if (!ok) nfail++;
  PetscFunctionReturn(0);
}

/* Check() with ok reduced over comm (logical and): collective on comm. The got and want printed are those of the first
   rank where the check fails (of rank 0 when it holds everywhere). */
static inline PetscErrorCode CheckAll(MPI_Comm comm, PetscBool ok, const char *what, PetscReal got, PetscReal want)
{
  PetscMPIInt rank, size, first;
  PetscReal   values[2] = {got, want};

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  first = ok ? size : rank;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, comm));
  if (first < size) PetscCallMPI(MPI_Bcast(values, 2, MPIU_REAL, first, comm));
  PetscCall(
      PetscPrintf(comm, "%s %-72s got %.10g want %.10g\n", first == size ? "ok  " : "FAIL", what, (double)values[0], (double)values[1]));
  if (first < size) nfail++;
  PetscFunctionReturn(0);
}

/* CheckAll() of a yes/no property: printed as got 0 or 1, want 1. Collective on comm. */
static inline PetscErrorCode CheckTrue(MPI_Comm comm, PetscBool ok, const char *what) { return CheckAll(comm, ok, what, ok ? 1 : 0, 1); }

/* Check() with a printf-style description. */
static inline PetscErrorCode Checkf(PetscBool ok, PetscReal got, PetscReal want, const char *fmt, ...)
{
  char    what[1024];
  size_t  len;
  va_list ap;

  PetscFunctionBeginUser;
  va_start(ap, fmt);
  PetscCall(PetscVSNPrintf(what, sizeof(what), fmt, &len, ap));
  va_end(ap);
  PetscCall(Check(ok, what, got, want));
  PetscFunctionReturn(0);
}

/* A fresh stepper on comm configured only by the given options (the options database is reset). An option that
   nothing read is refused, as kergs refuses it: a misspelt option would otherwise leave a test checking another case. */
static inline PetscErrorCode MakeStepperOn(MPI_Comm comm, const char *opts, KergsStepper *st)
{
  PetscInt n, unread;
  char   **names, **values;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsClear(NULL));
  PetscCall(PetscOptionsInsertString(NULL, opts));
  PetscCall(PetscOptionsInsertString(NULL, "-output_none -quiet"));
  PetscCall(KergsStepperCreate(comm, st));
  PetscCall(KergsStepperSetFromOptions(*st));
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  unread = n;
  for (PetscInt i = 0; i < n; i++) PetscCall(PetscPrintf(comm, "test: option -%s was not read (options: %s)\n", names[i], opts));
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscCheck(unread == 0, comm, PETSC_ERR_USER_INPUT, "%" PetscInt_FMT " option(s) of a test's stepper not read: misspelt?", unread);
  PetscFunctionReturn(0);
}

static inline PetscErrorCode MakeStepper(const char *opts, KergsStepper *st) { return MakeStepperOn(PETSC_COMM_WORLD, opts, st); }

/* The statistic `name` recorded for step row `row` (-1: the last step). */
static inline PetscErrorCode StatAt(KergsResults res, const char *name, PetscInt row, PetscReal *value)
{
  PetscFunctionBeginUser;
  *value = PETSC_MAX_REAL;
  if (row < 0) row = res->nrows - 1;
  for (PetscInt s = 0; s < res->nstats; s++) {
    PetscBool same;
    PetscCall(PetscStrcmp(res->statname[s], name, &same));
    if (same && row >= 0 && row < res->nrows) *value = res->statvalues[s][row];
  }
  PetscCheck(*value != PETSC_MAX_REAL, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "No statistic %s recorded for row %" PetscInt_FMT, name, row);
  PetscFunctionReturn(0);
}

/* Run nsteps of a stepper from its first step; the largest iteration count (sweeps, Newton steps, outer iterations) and
   the largest natural residual over the steps, and how many steps converged. */
static inline PetscErrorCode StepAndSummarize(KergsStepper st, PetscInt nsteps, PetscInt *maxits, PetscReal *maxres, PetscInt *nconverged)
{
  PetscReal its, res, conv;

  PetscFunctionBeginUser;
  *maxits = *nconverged = 0;
  *maxres               = 0;
  for (PetscInt s = 0; s < nsteps; s++) {
    PetscCall(KergsStepperStep(st));
    PetscCall(StatAt(st->results, "iterations", s, &its));
    PetscCall(StatAt(st->results, "residual", s, &res));
    PetscCall(StatAt(st->results, "converged", s, &conv));
    *maxits = PetscMax(*maxits, (PetscInt)its);
    *maxres = PetscMax(*maxres, res);
    *nconverged += conv > 0.5;
  }
  PetscFunctionReturn(0);
}

/* StepAndSummarize on a new stepper of a scene. The stepper is kept in *keep when asked, else destroyed. */
static inline PetscErrorCode RunSteps(const char *opts, PetscInt nsteps, KergsStepper *keep, PetscInt *maxits, PetscReal *maxres,
                                      PetscInt *nconverged)
{
  KergsStepper st;

  PetscFunctionBeginUser;
  *maxits = *nconverged = 0; /* set before anything can fail: gcc cannot see StepAndSummarize set them */
  *maxres               = 0;
  PetscCall(MakeStepper(opts, &st));
  PetscCall(StepAndSummarize(st, nsteps, maxits, maxres, nconverged));
  if (keep)
    *keep = st;
  else
    PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The Coulomb cone K = {(r_n, r_t): |r_t| <= mu r_n} (a half-line r_t = 0, r_n >= 0 when nc = 1): the Euclidean
   projection of z, written here from the geometry of the cone and its polar cone {mu |y_t| <= -y_n}, not taken
   from the library. */
static inline void TestProjectCone(PetscInt nc, const PetscReal z[], PetscReal mu, PetscReal p[])
{
  const PetscReal zt = nc > 1 ? z[1] : 0.0, azt = PetscAbsReal(zt);

  if (nc == 1 || mu == 0.0) { /* the half-line */
    p[0] = PetscMax(z[0], 0.0);
    if (nc > 1) p[1] = 0.0;
  } else if (azt <= mu * z[0]) { /* inside K */
    p[0] = z[0];
    p[1] = zt;
  } else if (mu * azt <= -z[0]) { /* inside the polar cone */
    p[0] = p[1] = 0.0;
  } else { /* onto the boundary ray (1, mu sign z_t) / sqrt(1 + mu^2) */
    const PetscReal s = (z[0] + mu * azt) / (1.0 + mu * mu);
    p[0]              = s;
    p[1]              = zt > 0 ? mu * s : -mu * s;
  }
}

/* The natural-map residual of the problem a step just solved, recomputed by the test from what the step left
   (docs/solver.md): v = W r + v^d with W assembled whole from the stored W (KergsOperatorsGetFullW), and per contact
   e = r - proj_K(r - rho (v + mu |v_t| e_n)) (De Saxce's modified velocity), rho = 1 / W_nn, e = r for an inactive
   contact; residual = |e|_2 / |r|_2 (|e|_2 when r = 0). Independent of the library's residual routines
   (KergsSweepNaturalResidual, KergsLawNaturalResidual2). W must still exist after the step: run with -keep_H (the
   kernel-regularised types keep it anyway); a released W is a set-up error of the test. Collective. */
static inline PetscErrorCode IndependentNaturalResidual(KergsStepper st, PetscReal *residual)
{
  KergsOperators     ops;
  KergsContacts      ct;
  KergsSolver        solver;
  KergsContact      *c;
  KergsDofLayout     L;
  const PetscBool   *active;
  Mat                W, Wfull;
  Vec                r, vd, v, diag;
  const PetscScalar *ra, *va, *da;
  PetscReal          sums[3] = {0, 0, 0};
  PetscInt           n, nc, nloc;

  PetscFunctionBeginUser;
  PetscCall(KergsStepperGetOperators(st, &ops));
  PetscCall(KergsStepperGetContacts(st, &ct));
  PetscCall(KergsStepperGetSolver(st, &solver));
  PetscCall(KergsOperatorsGetW(ops, &W, NULL));
  PetscCheck(W, PETSC_COMM_WORLD, PETSC_ERR_ORDER, "IndependentNaturalResidual: W was released after the step; run the scene with -keep_H");
  PetscCall(KergsOperatorsGetLayout(ops, &L));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, NULL, &vd));
  PetscCall(KergsContactsGetLocal(ct, &n, &c));
  PetscCall(KergsSolverGetActive(solver, &active));
  nc = L.ncomp;
  PetscCall(VecGetLocalSize(r, &nloc));
  PetscCheck(nloc == n * nc, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "IndependentNaturalResidual: %" PetscInt_FMT " impulse entries for %" PetscInt_FMT " contacts", nloc, n);
  PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
  PetscCall(VecDuplicate(r, &v));
  PetscCall(VecDuplicate(r, &diag));
  PetscCall(MatMult(Wfull, r, v));
  PetscCall(VecAXPY(v, 1.0, vd));
  PetscCall(MatGetDiagonal(Wfull, diag));
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArrayRead(v, &va));
  PetscCall(VecGetArrayRead(diag, &da));
  for (PetscInt k = 0; k < n; k++) {
    const PetscReal *rk = &ra[k * nc], *vk = &va[k * nc];
    PetscReal        e[KERGS_MAXCOMP], z[KERGS_MAXCOMP], p[KERGS_MAXCOMP];
    if (!active || active[k]) {
      const PetscReal rho = 1.0 / da[k * nc], mu = c[k].mu;
      z[0] = rk[0] - rho * (vk[0] + (nc > 1 ? mu * PetscAbsReal(vk[1]) : 0.0));
      if (nc > 1) z[1] = rk[1] - rho * vk[1];
      TestProjectCone(nc, z, mu, p);
      for (PetscInt d = 0; d < nc; d++) e[d] = rk[d] - p[d];
    } else
      for (PetscInt d = 0; d < nc; d++) e[d] = rk[d];
    for (PetscInt d = 0; d < nc; d++) {
      sums[0] += e[d] * e[d];
      sums[1] += rk[d] * rk[d];
      sums[2] += (rk[d] - e[d]) * (rk[d] - e[d]); /* the law's image p = r - e */
    }
  }
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(VecRestoreArrayRead(v, &va));
  PetscCall(VecRestoreArrayRead(diag, &da));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPIU_SUM, PETSC_COMM_WORLD));
  /* |e| / max(|r|, |p|), 0 when both vanish (docs/solver.md) */
  *residual = PetscMax(sums[1], sums[2]) > 0 ? PetscSqrtReal(sums[0] / PetscMax(sums[1], sums[2])) : 0.0;
  PetscCall(VecDestroy(&v));
  PetscCall(VecDestroy(&diag));
  PetscCall(MatDestroy(&Wfull));
  PetscFunctionReturn(0);
}

/* A per-disk field of the owned disks (bs values per disk) gathered over the ranks into grain-id order on every
   rank (out: bs * ndisks values; the grain ids must be 0 .. ndisks-1). Independent of the partition, so that runs
   on different numbers of ranks compare grain by grain. */
static inline PetscErrorCode GatherById(KergsScene sc, const PetscReal *owned, PetscInt bs, PetscReal *out)
{
  PetscReal *all;
  PetscInt  *ids;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(bs * sc->ndisks + 1, &all, sc->ndisks + 1, &ids));
  PetscCall(KergsSceneAllGatherReal(sc, owned, bs, all));
  PetscCall(KergsSceneAllGatherInt(sc, sc->id, 1, ids));
  for (PetscInt g = 0; g < sc->ndisks; g++) {
    PetscCheck(ids[g] >= 0 && ids[g] < sc->ndisks, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "GatherById: grain id %" PetscInt_FMT " outside [0, %" PetscInt_FMT ")", ids[g], sc->ndisks);
    for (PetscInt d = 0; d < bs; d++) out[bs * ids[g] + d] = all[bs * g + d];
  }
  PetscCall(PetscFree2(all, ids));
  PetscFunctionReturn(0);
}

/* The largest difference between the disks' velocities of two runs of one scene, grain by grain (GatherById: any
   partitions, any numbers of ranks), and the largest velocity of the second run, the reference. */
static inline PetscErrorCode VelocityDifference(KergsStepper a, KergsStepper b, PetscReal *diff, PetscReal *scale)
{
  const PetscInt n = KERGS_DIM * b->scene->ndisks;
  PetscReal     *va, *vb;

  PetscFunctionBeginUser;
  PetscCheck(a->scene->ndisks == b->scene->ndisks, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "VelocityDifference: two scenes of different sizes");
  PetscCall(PetscMalloc2(n + 1, &va, n + 1, &vb));
  PetscCall(GatherById(a->scene, a->scene->v, KERGS_DIM, va));
  PetscCall(GatherById(b->scene, b->scene->v, KERGS_DIM, vb));
  *diff = *scale = 0.0;
  for (PetscInt i = 0; i < n; i++) {
    *diff  = PetscMax(*diff, PetscAbsReal(va[i] - vb[i]));
    *scale = PetscMax(*scale, PetscAbsReal(vb[i]));
  }
  PetscCall(PetscFree2(va, vb));
  PetscFunctionReturn(0);
}

/* One disk and one wall, 5 steps each with the solver that `solver` sets up (type, tolerance 1e-10 and its own options),
   `label` naming it in the checks: open (moving away), resting (closing, stick), on a slope below and above tan = mu
   (stick, slip; rotation locked). Every step converged to 1e-10, and the physics right: it flies off, it is at rest, or
   it slides down at g (sin - mu cos). The accurate types tresca and snesvi run it; newton's own test also bounds its
   Newton steps. */
static inline PetscErrorCode CheckOneContactCases(const char *solver, const char *label)
{
  const char *disk = "-gravity 0,-10 -dt 1e-3 -disks_source list -disks_radius 0.1 -alert 0.01 -friction 0.5";
  struct {
    const char *what, *opts;
  } cases[] = {
      {"open (the disk leaves the floor)", "-disks_x 0,0.1 -disks_velocity 0,5 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      {"stick (the disk rests on the floor)", "-disks_x 0,0.0999999 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      {"stick on a slope (tan 0.31 < mu 0.5)", "-disks_lock_rotation -disks_x -0.029552,0.095534 -walls slope -wall_slope_a "
                                               "-9.553365,-2.955202 -wall_slope_b 9.553365,2.955202 -wall_slope_infinite"},
      {"slip on a slope (tan 0.84 > mu 0.5)", "-disks_lock_rotation -disks_x -0.064422,0.076484 -walls slope -wall_slope_a "
                                              "-7.648422,-6.442177 -wall_slope_b 7.648422,6.442177 -wall_slope_infinite"},
  };

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
    PetscInt     maxits, nconv;
    PetscReal    maxres, v[KERGS_DIM];
    KergsStepper st;
    char         opts[1024];
    PetscCall(PetscSNPrintf(opts, sizeof(opts), "%s %s %s -steps 5", disk, cases[i].opts, solver));
    PetscCall(RunSteps(opts, 5, &st, &maxits, &maxres, &nconv));
    PetscCall(Checkf((PetscBool)(nconv == 5 && maxres <= 1e-10), maxres, 1e-10, "%s, one contact, %s: 5 steps converged (largest residual)",
                     label, cases[i].what));
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->v, KERGS_DIM, v));
    if (i == 0)
      PetscCall(Checkf((PetscBool)(v[1] > 4.9), v[1], 4.95, "%s, one contact, %s: flies off, only gravity slows it", label, cases[i].what));
    if (i == 1 || i == 2)
      PetscCall(Checkf((PetscBool)(PetscAbsReal(v[0]) + PetscAbsReal(v[1]) < 1e-9), PetscAbsReal(v[0]) + PetscAbsReal(v[1]), 0,
                       "%s, one contact, %s: at rest", label, cases[i].what));
    if (i == 3) { /* slides down at g (sin - mu cos), 5 steps */
      const PetscReal a = 0.7, want = 10 * (PetscSinReal(a) - 0.5 * PetscCosReal(a)) * 5e-3,
                      got = -(v[0] * PetscCosReal(a) + v[1] * PetscSinReal(a));
      PetscCall(Checkf((PetscBool)(PetscAbsReal(got - want) < 1e-6 * want), got, want, "%s, one contact, %s: slides at g(sin - mu cos)",
                       label, cases[i].what));
    }
    PetscCall(KergsStepperDestroy(&st));
  }
  PetscFunctionReturn(0);
}

/* The closing line and the exit code of a test program. */
static inline int Finish(void)
{
  PetscCallAbort(PETSC_COMM_WORLD,
                 PetscPrintf(PETSC_COMM_WORLD, "%s: %" PetscInt_FMT " failed checks\n", nfail ? "FAILED" : "PASSED", nfail));
  return nfail ? 1 : 0;
}

#endif
