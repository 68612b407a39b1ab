/* The kernel projector P = I - H_f^T (H_f H_f^T)^+ H_f on packings built by the engine: projector identities,
   the rank of H_f and its causes against a dense eigenvalue computation, exact diagonal blocks of Z against
   P e_j column by column, the cheap bound, symbolic reuse, empty and fully peeled cases, collinear contacts
   (null pivots). Runs on 1 and 2 ranks; every check is global. Timings on a few thousand grains are a benchmark
   (scripts/bench_micro.c). */
static const char help[] = "kergs kernel projector tests.\n";

#include "testing.h"
#include "internals.h"
#include <petscblaslapack.h>

/* This step's contacts and operators at the current positions. */
static PetscErrorCode Assemble(KergsStepper st)
{
  PetscFunctionBeginUser;
  PetscCall(KergsContactsDetect(st->contacts, st->scene));
  PetscCall(KergsOperatorsAssemble(st->ops, st->scene, st->contacts));
  PetscFunctionReturn(0);
}

static PetscErrorCode MakeKernel(const char *opts, KergsStepper st, KergsKernel *k)
{
  PetscFunctionBeginUser;
  PetscCall(PetscOptionsInsertString(NULL, opts));
  PetscCall(KergsKernelCreate(PETSC_COMM_WORLD, k));
  PetscCall(KergsKernelSetFromOptions(*k));
  PetscCall(KergsKernelSetUp(*k, st->scene, st->contacts, st->ops));
  PetscFunctionReturn(0);
}

/* The rank of H_f from the eigenvalues of the dense H_f D^2 H_f^T (D: 1/radius on rotations, a row scaling that
   keeps the rank and makes the entries of one unit), replicated; eigenvalues below 1e-10 of the largest are 0.
   Also returns the largest "zero" and the smallest non-zero eigenvalue, relative, to show the gap. */
static PetscErrorCode DenseRank(KergsStepper st, PetscInt *rank, PetscReal *zero, PetscReal *nonzero)
{
  KergsOperators ops = st->ops;
  PetscInt       n   = ops->nfree, lo, hi;
  PetscReal     *G, *w, *work, *scale;
  PetscMPIInt    r;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &r));
  PetscCall(PetscCalloc3(n * n + 1, &G, n + 1, &w, n + 1, &scale));
  for (PetscInt g = 0; g < n; g++) scale[g] = 1.0;
  {
    PetscReal *radius; /* by global index */
    PetscCall(PetscMalloc1(st->scene->ndisks + 1, &radius));
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->radius, 1, radius));
    for (PetscInt i = 0; i < st->scene->ndisks; i++)
      for (PetscInt d = KERGS_DIM; d < ops->ndof_disk; d++) scale[KergsOperatorsDiskDof(ops, i) + d] = 1.0 / radius[i];
    PetscCall(PetscFree(radius));
  }
  PetscCall(MatGetOwnershipRange(ops->HfT, &lo, &hi));
  for (PetscInt row = lo; row < hi; row++) {
    const PetscInt    *cols;
    const PetscScalar *vals;
    PetscInt           nc;
    PetscCall(MatGetRow(ops->HfT, row, &nc, &cols, &vals));
    for (PetscInt i = 0; i < nc; i++)
      for (PetscInt j = 0; j < nc; j++) G[cols[i] * n + cols[j]] += vals[i] * scale[cols[i]] * vals[j] * scale[cols[j]];
    PetscCall(MatRestoreRow(ops->HfT, row, &nc, &cols, &vals));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, G, n * n, MPIU_REAL, MPI_SUM, PETSC_COMM_WORLD));
  *rank = 0, *zero = 0, *nonzero = 0;
  if (!r && n > 0) {
    PetscBLASInt bn, lwork, info;
    PetscReal    wmax;
    PetscCall(PetscBLASIntCast(n, &bn));
    PetscCall(PetscBLASIntCast(8 * n, &lwork));
    PetscCall(PetscMalloc1(8 * n, &work));
    LAPACKsyev_("N", "U", &bn, G, &bn, w, work, &lwork, &info);
    PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK syev failed: info %d", (int)info);
    PetscCall(PetscFree(work));
    wmax     = w[n - 1];
    *nonzero = 1;
    for (PetscInt i = 0; i < n; i++) {
      if (w[i] > 1e-10 * wmax) {
        (*rank)++;
        *nonzero = PetscMin(*nonzero, w[i] / wmax);
      } else
        *zero = PetscMax(*zero, PetscAbsReal(w[i]) / wmax);
    }
  }
  PetscCallMPI(MPI_Bcast(rank, 1, MPIU_INT, 0, PETSC_COMM_WORLD));
  PetscCallMPI(MPI_Bcast(zero, 1, MPIU_REAL, 0, PETSC_COMM_WORLD));
  PetscCallMPI(MPI_Bcast(nonzero, 1, MPIU_REAL, 0, PETSC_COMM_WORLD));
  PetscCall(PetscFree3(G, w, scale));
  PetscFunctionReturn(0);
}

/* On pseudo-random x, y: |H_f P x| / |x|, |P P x - P x| / |x|, <P x, y> - <x, P y>, |P x| <= |x|, and Z = omega P. */
static PetscErrorCode CheckProjector(const char *name, KergsKernel k, KergsStepper st)
{
  KergsOperators ops = st->ops;
  Vec            x, y, Px, Py, PPx, HPx, Zx;
  PetscRandom    rnd;
  PetscReal      nx, ny, nHPx, nPx, dPP, pxy, xpy, dZ;
  Mat            Z;
  char           what[256];

  PetscFunctionBeginUser;
  PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1, 1));
  PetscCall(PetscRandomSetSeed(rnd, 1234));
  PetscCall(PetscRandomSeed(rnd));
  PetscCall(VecDuplicate(ops->r, &x));
  PetscCall(VecDuplicate(ops->r, &y));
  PetscCall(VecDuplicate(ops->r, &Px));
  PetscCall(VecDuplicate(ops->r, &Py));
  PetscCall(VecDuplicate(ops->r, &PPx));
  PetscCall(VecDuplicate(ops->r, &Zx));
  PetscCall(VecDuplicate(ops->Vf, &HPx));
  PetscCall(VecSetRandom(x, rnd));
  PetscCall(VecSetRandom(y, rnd));
  PetscCall(KergsKernelProject(k, x, Px));
  PetscCall(KergsKernelProject(k, y, Py));
  PetscCall(KergsKernelProject(k, Px, PPx));
  PetscCall(MatMultTranspose(ops->HfT, Px, HPx));
  PetscCall(VecNorm(x, NORM_2, &nx));
  PetscCall(VecNorm(y, NORM_2, &ny));
  PetscCall(VecNorm(HPx, NORM_2, &nHPx));
  PetscCall(VecNorm(Px, NORM_2, &nPx));
  PetscCall(VecAXPY(PPx, -1.0, Px));
  PetscCall(VecNorm(PPx, NORM_2, &dPP));
  PetscCall(VecDot(Px, y, &pxy));
  PetscCall(VecDot(x, Py, &xpy));
  PetscCall(KergsKernelGetZ(k, &Z));
  PetscCall(MatMult(Z, x, Zx));
  PetscCall(VecAXPY(Zx, -k->omega, Px));
  PetscCall(VecNorm(Zx, NORM_2, &dZ));
  if (nx == 0) nx = ny = 1; /* no contact: empty vectors */
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: |H_f P x| / |x|", name));
  PetscCall(Check((PetscBool)(nHPx / nx <= 1e-10), what, nHPx / nx, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: |P P x - P x| / |x|", name));
  PetscCall(Check((PetscBool)(dPP / nx <= 1e-10), what, dPP / nx, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: |<P x, y> - <x, P y>| / |x||y|", name));
  PetscCall(Check((PetscBool)(PetscAbsReal(pxy - xpy) / (nx * ny) <= 1e-10), what, PetscAbsReal(pxy - xpy) / (nx * ny), 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: |P x| <= |x|", name));
  PetscCall(Check((PetscBool)(nPx <= nx * (1 + 1e-12)), what, nPx, nx));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: Z x = omega P x", name));
  PetscCall(Check((PetscBool)(dZ <= 1e-12 * k->omega * nx), what, dZ, 0));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(VecDestroy(&Px));
  PetscCall(VecDestroy(&Py));
  PetscCall(VecDestroy(&PPx));
  PetscCall(VecDestroy(&Zx));
  PetscCall(VecDestroy(&HPx));
  PetscCall(PetscRandomDestroy(&rnd));
  PetscFunctionReturn(0);
}

/* The kernel's rank against the dense one, and the deficiency identity
   rows - rank = DOFs without contact + deficiency of the peeled grains + null pivots. */
static PetscErrorCode CheckRank(const char *name, KergsKernel k, KergsStepper st)
{
  PetscInt  rank;
  PetscReal zero, nonzero;
  char      what[256];

  PetscFunctionBeginUser;
  PetscCall(DenseRank(st, &rank, &zero, &nonzero));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "     %s: H_f %" PetscInt_FMT " x %" PetscInt_FMT ", %" PetscInt_FMT " grains without contact, %" PetscInt_FMT
                        " with one contact, %" PetscInt_FMT " peeled contacts (deficiency %" PetscInt_FMT "), %" PetscInt_FMT
                        " null pivots; dense eigenvalue gap %.2g / %.2g\n",
                        name, k->nrows, k->ncols, k->floating_grains, k->single_contact_grains, k->peeled_contacts, k->deficiency_peeled,
                        k->null_pivots, (double)zero, (double)nonzero));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: rank of H_f = dense rank", name));
  PetscCall(Check((PetscBool)(k->rank == rank), what, k->rank, rank));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: rows - rank = floating DOFs + peeled deficiency + null pivots", name));
  PetscCall(Check((PetscBool)(k->nrows - k->rank == k->floating_dofs + k->deficiency_peeled + k->null_pivots), what, k->nrows - k->rank,
                  k->floating_dofs + k->deficiency_peeled + k->null_pivots));
  PetscFunctionReturn(0);
}

/* P e_j column by column: the diagonal blocks omega P_aa against kernel->Zdiag (exact), trace P = dimension of
   ker H_f, and the bound's diagonal entries between the exact ones and omega, its off-diagonal entries 0. */
static PetscErrorCode CheckDiagonal(const char *name, KergsKernel k, KergsStepper st)
{
  KergsOperators ops = st->ops;
  PetscInt       nc = ops->ncomp, lo, hi, nb = nc * nc, nl = st->contacts->n;
  Vec            e, Pe;
  PetscReal     *ref, *exact, trace = 0, err = 0, below = 0, above = 0, offdiag = 0, tex, tbd;
  char           what[256];

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(ops->r, &e));
  PetscCall(VecDuplicate(ops->r, &Pe));
  PetscCall(VecGetOwnershipRange(e, &lo, &hi));
  PetscCall(PetscCalloc2(nl * nb + 1, &ref, nl * nb + 1, &exact));
  for (PetscInt j = 0; j < k->ncols; j++) {
    const PetscScalar *p;
    PetscCall(VecSet(e, 0.0));
    if (j >= lo && j < hi) PetscCall(VecSetValue(e, j, 1.0, INSERT_VALUES));
    PetscCall(VecAssemblyBegin(e));
    PetscCall(VecAssemblyEnd(e));
    PetscCall(KergsKernelProject(k, e, Pe));
    PetscCall(VecGetArrayRead(Pe, &p));
    if (j >= lo && j < hi) {
      PetscInt a = (j - lo) / nc, d = (j - lo) % nc;
      trace += p[j - lo];
      for (PetscInt c = 0; c < nc; c++) ref[a * nb + c * nc + d] = k->omega * p[a * nc + c];
    }
    PetscCall(VecRestoreArrayRead(Pe, &p));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &trace, 1, MPIU_REAL, MPI_SUM, PETSC_COMM_WORLD));
  k->diagtype = KERGS_KERNEL_DIAG_EXACT;
  PetscCall(KergsKernelComputeDiagonalBlocks(k));
  tex = k->diag_seconds;
  for (PetscInt i = 0; i < nl * nb; i++) err = PetscMax(err, PetscAbsReal(k->Zdiag[i] - ref[i]));
  PetscCall(PetscArraycpy(exact, k->Zdiag, nl * nb));
  k->diagtype = KERGS_KERNEL_DIAG_BOUND;
  PetscCall(KergsKernelComputeDiagonalBlocks(k));
  tbd = k->diag_seconds;
  for (PetscInt a = 0; a < nl; a++)
    for (PetscInt c = 0; c < nc; c++)
      for (PetscInt d = 0; d < nc; d++) {
        PetscReal b = k->Zdiag[a * nb + c * nc + d];
        if (c != d)
          offdiag = PetscMax(offdiag, PetscAbsReal(b));
        else {
          below = PetscMax(below, exact[a * nb + c * nc + c] - b);
          above = PetscMax(above, b - k->omega);
        }
      }
  k->diagtype = KERGS_KERNEL_DIAG_EXACT;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &below, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &above, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &offdiag, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: trace P = dimension of ker H_f", name));
  PetscCall(Check((PetscBool)(PetscAbsReal(trace - (k->ncols - k->rank)) < 1e-8), what, trace, k->ncols - k->rank));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: exact Z_aa = omega P_aa from P e_j (max error)", name));
  PetscCall(Check((PetscBool)(err <= 1e-10 * k->omega), what, err, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: bound >= exact - 1e-12 (largest exact - bound)", name));
  PetscCall(Check((PetscBool)(below <= 1e-12 * k->omega), what, below, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: bound <= omega (largest bound - omega)", name));
  PetscCall(Check((PetscBool)(above <= 0), what, above, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: bound's off-diagonal entries are 0", name));
  PetscCall(Check((PetscBool)(offdiag == 0), what, offdiag, 0));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "     %s: diagonal blocks exact %.3g s, bound %.3g s\n", name, (double)tex, (double)tbd));
  PetscCall(PetscFree2(ref, exact));
  PetscCall(VecDestroy(&e));
  PetscCall(VecDestroy(&Pe));
  PetscFunctionReturn(0);
}

/* Keep only the disks of the shipped 500-disk deposit whose centre lies in [0, xmax] x [0, ymax] (a small
   real packing with grains left with one contact by the cut), plus two grains without contact. */
static PetscErrorCode DepositWindow(const char *extra, PetscReal xmax, PetscReal ymax, KergsStepper *st)
{
  char       opts[1024];
  KergsScene sc;
  PetscReal *x, *r, *xall, *rall;
  PetscInt   n = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(
      opts, sizeof(opts),
      "-options_file cases/confine500.opts -solver_type nlgs -solver_max_it 150 -solver_tol 1e-4 -wall_box_right_velocity 0,0 %s", extra));
  PetscCall(MakeStepper(opts, st));
  sc = (*st)->scene;
  PetscCall(PetscMalloc4(KERGS_DIM * (sc->ndisks + 2), &x, sc->ndisks + 2, &r, KERGS_DIM * sc->ndisks + 1, &xall, sc->ndisks + 1, &rall));
  PetscCall(KergsSceneAllGatherReal(sc, sc->x, KERGS_DIM, xall)); /* the whole deposit, on every rank */
  PetscCall(KergsSceneAllGatherReal(sc, sc->radius, 1, rall));
  for (PetscInt i = 0; i < sc->ndisks; i++)
    if (xall[KERGS_DIM * i] <= xmax && xall[KERGS_DIM * i + 1] <= ymax) {
      for (PetscInt d = 0; d < KERGS_DIM; d++) x[KERGS_DIM * n + d] = xall[KERGS_DIM * i + d];
      r[n++] = rall[i];
    }
  /* two rattlers far above the window: grains without contact */
  for (PetscInt j = 0; j < 2; j++) {
    x[KERGS_DIM * n]     = 0.1 + 0.2 * j;
    x[KERGS_DIM * n + 1] = 0.8;
    r[n++]               = 0.015;
  }
  PetscCall(KergsSceneSetDisks(sc, n, x, r, NULL, NULL));
  PetscCall(PetscFree4(x, r, xall, rall));
  PetscCall(Assemble(*st));
  PetscFunctionReturn(0);
}

/* A frictional window of the deposit: floating and single-contact grains, peeling, rank, projector, diagonal
   blocks; then a second SetUp on the same operators must reuse the symbolic factorization. */
static PetscErrorCode TestDepositWindow(PetscBool frictional)
{
  KergsStepper st;
  KergsKernel  k;
  const char  *name = frictional ? "window, frictional" : "window, frictionless";
  char         what[256];
  PetscInt     reuses;

  PetscFunctionBeginUser;
  PetscCall(DepositWindow(frictional ? "" : "-friction 0", 0.3, 0.16, &st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(KergsKernelSetOmega(k, 2.5));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: components per contact", name));
  PetscCall(Check((PetscBool)(k->ncomp == (frictional ? 2 : 1)), what, k->ncomp, frictional ? 2 : 1));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: some grains float, some are peeled", name));
  PetscCall(Check((PetscBool)(k->floating_grains > 0 && k->peeled_contacts > 0), what, k->floating_grains * k->peeled_contacts, 1));
  PetscCall(CheckRank(name, k, st));
  PetscCall(CheckProjector(name, k, st));
  PetscCall(CheckDiagonal(name, k, st));
  reuses = k->symbolic_reuses;
  PetscCall(KergsKernelSetUp(k, st->scene, st->contacts, st->ops));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: same pattern reuses the symbolic factorization", name));
  PetscCall(Check((PetscBool)(k->symbolic_reuses == reuses + 1), what, k->symbolic_reuses, reuses + 1));
  PetscCall(CheckProjector(name, k, st));
  PetscCall(KergsKernelView(k, PETSC_VIEWER_STDOUT_WORLD));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The whole 500-disk deposit (the paper's kind of sample, Figure 5), after two steps of confinement. */
static PetscErrorCode TestDeposit500(void)
{
  KergsStepper st;
  KergsKernel  k;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-options_file cases/confine500.opts -solver_type nlgs -solver_max_it 150 -solver_tol 1e-4", &st));
  for (PetscInt s = 0; s < 2; s++) PetscCall(KergsStepperStep(st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("-kernel_diag bound", st, &k));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "     deposit500 (paper: H_f 1500 x 2044, rank 1487, 2 grains without contact, 7 with one): H_f %" PetscInt_FMT
                        " x %" PetscInt_FMT ", rank %" PetscInt_FMT ", %" PetscInt_FMT " without contact, %" PetscInt_FMT " with one\n",
                        k->nrows, k->ncols, k->rank, k->floating_grains, k->single_contact_grains));
  PetscCall(CheckRank("deposit500", k, st));
  PetscCall(CheckProjector("deposit500", k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The paper's pathological wedge: 4 contacts (8 components) on 6 DOFs, rank 6, a 2-dimensional kernel. */
static PetscErrorCode TestWedged(void)
{
  KergsStepper st;
  KergsKernel  k;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-options_file cases/two_disks_wedged.opts", &st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(KergsKernelSetOmega(k, 0.7));
  PetscCall(Check((PetscBool)(k->ncols == 8 && k->nrows == 6), "wedged pair: H_f is 6 x 8", k->ncols * 10 + k->nrows, 86));
  PetscCall(Check((PetscBool)(k->ncols - k->rank == 2), "wedged pair: kernel dimension 2", k->ncols - k->rank, 2));
  PetscCall(CheckRank("wedged pair", k, st));
  PetscCall(CheckProjector("wedged pair", k, st));
  PetscCall(CheckDiagonal("wedged pair", k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* A touching hexagonal crystal in a box that fits it, compressed by the top and right walls for a few steps:
   no floating nor peeled grain, a large kernel. */
static PetscErrorCode TestHexCrystal(void)
{
  KergsStepper st;
  KergsKernel  k;

  PetscFunctionBeginUser;
  PetscCall(
      MakeStepper("-gravity 0,-9.81 -friction 0.3 -dt 1e-4 -disks_source lattice -lattice_type hex -lattice_n 10,8 -lattice_radius 0.005 "
                  "-lattice_origin 0.005,0.005 -box 0,0,0.105,0.0706218 -wall_box_top_velocity 0,-0.05 -wall_box_right_velocity -0.05,0 "
                  "-alert 5e-4 -solver_max_it 100",
                  &st));
  for (PetscInt s = 0; s < 3; s++) PetscCall(KergsStepperStep(st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(Check((PetscBool)(k->floating_grains == 0 && k->peeled_contacts == 0), "hex crystal: no grain floats or is peeled",
                  k->floating_grains + k->peeled_contacts, 0));
  PetscCall(Check((PetscBool)(k->rank == k->nrows), "hex crystal: H_f has full row rank", k->rank, k->nrows));
  PetscCall(CheckRank("hex crystal", k, st));
  PetscCall(CheckProjector("hex crystal", k, st));
  PetscCall(CheckDiagonal("hex crystal", k, st));
  /* the next step has new operators with the same contacts: only the numeric factorization is redone */
  PetscCall(KergsStepperStep(st));
  PetscCall(Assemble(st));
  PetscCall(KergsKernelSetUp(k, st->scene, st->contacts, st->ops));
  PetscCall(Check((PetscBool)(k->symbolic_reuses == 1), "hex crystal, next step: symbolic factorization reused", k->symbolic_reuses, 1));
  PetscCall(CheckProjector("hex crystal, next step", k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Every grain floats (no contact at all): empty vectors, rank 0, nothing to factor. Then a column on a floor:
   a tree of contacts, every contact peeled, P = 0 and H_f has full column rank. */
static PetscErrorCode TestNoKernel(void)
{
  KergsStepper st;
  KergsKernel  k;
  PetscInt     n;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper(
      "-gravity 0,0 -friction 0.3 -disks_source lattice -lattice_type square -lattice_n 4,3 -lattice_radius 0.1 -lattice_spacing 0.5",
      &st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(Check((PetscBool)(k->ncols == 0 && k->rank == 0 && k->floating_grains == 12),
                  "all floating: no column, rank 0, 12 grains without contact", k->ncols + k->rank, 0));
  PetscCall(Check((PetscBool)(k->nrows - k->rank == k->floating_dofs), "all floating: deficiency = every DOF", k->nrows - k->rank,
                  k->floating_dofs));
  PetscCall(CheckProjector("all floating", k, st));
  PetscCall(KergsKernelComputeDiagonalBlocks(k));
  PetscCall(KergsKernelView(k, PETSC_VIEWER_STDOUT_WORLD));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));

  PetscCall(MakeStepper("-gravity 0,-10 -friction 0.3 -dt 1e-3 -disks_source lattice -lattice_type square -lattice_n 1,5 -lattice_radius "
                        "0.1 -lattice_origin 0,0.1 "
                        "-walls floor -wall_floor_a -1,0 -wall_floor_b 1,0 -wall_floor_infinite -alert 0.01",
                        &st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(Check((PetscBool)(k->peeled_contacts == 5 && k->ncols == 10), "column: all 5 contacts peeled", k->peeled_contacts, 5));
  PetscCall(Check((PetscBool)(k->rank == k->ncols), "column: H_f has full column rank (empty kernel)", k->rank, k->ncols));
  PetscCall(CheckRank("column", k, st));
  PetscCall(CheckProjector("column", k, st));
  {
    Vec       x, Px;
    PetscReal nPx;
    PetscCall(VecDuplicate(st->ops->r, &x));
    PetscCall(VecDuplicate(st->ops->r, &Px));
    PetscCall(VecSet(x, 1.0));
    PetscCall(KergsKernelProject(k, x, Px));
    PetscCall(VecNorm(Px, NORM_2, &nPx));
    PetscCall(Check((PetscBool)(nPx == 0), "column: P = 0", nPx, 0));
    PetscCall(VecGetLocalSize(x, &n));
    PetscCall(VecDestroy(&x));
    PetscCall(VecDestroy(&Px));
  }
  PetscCall(CheckDiagonal("column", k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Four frictionless disks in a row along the diagonal (1,1), between two walls perpendicular to it: every
   contact normal is the same direction, so each disk's motion across the row is a null direction of
   H_f H_f^T (4 null pivots), H_f (8 x 5) has rank 4, and the kernel is the row's uniform compression. */
static PetscErrorCode TestCollinear(const char *solver)
{
  KergsStepper st;
  KergsKernel  k;
  char         opts[2048], kopts[64], name[64];
  PetscReal    u = PetscSqrtReal(0.5), x[8], L = 4.0, s = 3.0;
  PetscMPIInt  size;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < 4; i++) x[2 * i] = x[2 * i + 1] = (0.5 + i) * u;
  PetscCall(PetscSNPrintf(
      opts, sizeof(opts),
      "-gravity 0,0 -disks_source list -disks_radius 0.5 -disks_x %.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g -walls lo,hi "
      "-wall_lo_a %.17g,%.17g -wall_lo_b %.17g,%.17g -wall_lo_infinite -wall_hi_a %.17g,%.17g -wall_hi_b %.17g,%.17g -wall_hi_infinite",
      x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], -s * u, s * u, s * u, -s * u, L * u + s * u, L * u - s * u, L * u - s * u,
      L * u + s * u));
  PetscCall(MakeStepper(opts, &st));
  PetscCall(Assemble(st));
  PetscCall(PetscSNPrintf(kopts, sizeof(kopts), "-kernel_solver %s", solver));
  PetscCall(PetscSNPrintf(name, sizeof(name), "collinear (%s)", solver));
  PetscCall(MakeKernel(kopts, st, &k));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(Check((PetscBool)(k->ncols == 5 && k->nrows == 8 && k->rank == 4), "collinear: H_f 8 x 5 of rank 4", k->rank, 4));
  PetscCall(Check((PetscBool)(k->null_pivots == 4), "collinear: 4 null pivots found by MUMPS", k->null_pivots, 4));
  PetscCall(Check((PetscBool)(!strcmp(k->used, MATSOLVERMUMPS)), "collinear: factored by MUMPS in the end", 0, 0));
  if (!strcmp(solver, "cholmod")) PetscCall(Check(k->fell_back, "collinear: CHOLMOD fell back to MUMPS", k->fell_back, 1));
  PetscCall(CheckRank(name, k, st));
  PetscCall(CheckProjector(name, k, st));
  PetscCall(CheckDiagonal(name, k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Two frictional disks in a horizontal row between two walls: 6 DOFs, 6 components, but the 3 tangential
   components cannot span the 4 vertical and rotational DOFs: H_f H_f^T is singular although it is square. */
static PetscErrorCode TestFrictionalRow(void)
{
  KergsStepper st;
  KergsKernel  k;
  PetscMPIInt  size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(MakeStepper("-gravity 0,0 -friction 0.5 -disks_source list -disks_radius 0.5 -disks_x 0.5,1,1.5,1 -walls left,right "
                        "-wall_left_a 0,3 -wall_left_b 0,0 -wall_left_infinite -wall_right_a 2,0 -wall_right_b 2,3 -wall_right_infinite",
                        &st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(Check((PetscBool)(k->kept_comps == 6 && k->kept_dofs == 6), "frictional row: H_f is 6 x 6", k->kept_comps, 6));
  PetscCall(Check((PetscBool)(k->null_pivots == 1 && k->rank == 5), "frictional row: one null pivot, rank 5", k->rank, 5));
  if (size == 1) PetscCall(Check(k->fell_back, "frictional row: CHOLMOD rejected for MUMPS", k->fell_back, 1));
  PetscCall(CheckRank("frictional row", k, st));
  PetscCall(CheckProjector("frictional row", k, st));
  PetscCall(CheckDiagonal("frictional row", k, st));
  /* after a rejection CHOLMOD rests: the next set-up goes to MUMPS directly and keeps its analysis */
  PetscCall(KergsKernelSetUp(k, st->scene, st->contacts, st->ops));
  PetscCall(Check((PetscBool)(!k->fell_back && !strcmp(k->used, MATSOLVERMUMPS) && k->symbolic_reuses == 1),
                  "frictional row, again: MUMPS reused, no new CHOLMOD attempt", k->symbolic_reuses, 1));
  PetscCall(CheckProjector("frictional row, again", k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* A guided wall (a pressure wall: it moves along its normal only) has rows of H_f along its normal: with friction,
   its single contact is not peeled, since the wall does not balance that contact's tangential impulse. Three disks in
   a pyramid on a floor, between a fixed wall and a guided one touching one disk: the rank against the dense one
   (peeling that contact would take 2 from the kernel's dimension), the projector identities, and one kept row of the
   wall's two. */
static PetscErrorCode TestGuidedWall(void)
{
  KergsStepper st;
  KergsKernel  k;

  PetscFunctionBeginUser;
  PetscCall(
      MakeStepper("-gravity 0,0 -friction 0.5 -disks_source list -disks_radius 0.5 -disks_x 0.5,0.5,1.5,0.5,1,1.3660254037844386 "
                  "-walls floor,left,right -wall_floor_a 0,0 -wall_floor_b 2,0 -wall_floor_infinite -wall_left_a 0,3 -wall_left_b 0,0 "
                  "-wall_left_infinite -wall_right_a 2,0 -wall_right_b 2,3 -wall_right_infinite -wall_right_type free "
                  "-wall_right_mass 1 -wall_right_pressure 1 -alert 1e-6",
                  &st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(Check((PetscBool)(k->peeled_contacts == 0), "guided wall: its single frictional contact is not peeled", k->peeled_contacts, 0));
  PetscCall(Check((PetscBool)(k->kept_dofs == 10), "guided wall: 3 disks x 3 DOFs and one of the wall's", k->kept_dofs, 10));
  PetscCall(CheckRank("guided wall", k, st));
  PetscCall(CheckProjector("guided wall", k, st));
  PetscCall(CheckDiagonal("guided wall", k, st));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* A frictionless hexagonal patch without walls: more contact components than DOFs, yet H_f H_f^T is singular by
   the patch's rigid motions (two translations and the rotation, which frictionless contacts do not see).
   The automatic solver tries CHOLMOD on one rank, which must be rejected for MUMPS. */
static PetscErrorCode TestFreePatch(void)
{
  KergsStepper st;
  KergsKernel  k;
  PetscMPIInt  size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(MakeStepper("-gravity 0,0 -disks_source lattice -lattice_type hex -lattice_n 5,4 -lattice_radius 0.5", &st));
  PetscCall(Assemble(st));
  PetscCall(MakeKernel("", st, &k));
  PetscCall(
      Check((PetscBool)(k->kept_comps >= k->kept_dofs), "free patch: more contact components than DOFs", k->kept_comps, k->kept_dofs));
  PetscCall(Check((PetscBool)(k->null_pivots >= 3), "free patch: rigid motions are null pivots", k->null_pivots, 3));
  if (size == 1) PetscCall(Check(k->fell_back, "free patch: CHOLMOD rejected for MUMPS", k->fell_back, 1));
  PetscCall(CheckRank("free patch", k, st));
  PetscCall(CheckProjector("free patch", k, st));
  PetscCall(CheckDiagonal("free patch", k, st));
  PetscCall(KergsKernelView(k, PETSC_VIEWER_STDOUT_WORLD));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* -kernel_solver cholmod on several ranks is refused with a message naming the option. */
static PetscErrorCode TestCholmodParallel(void)
{
  KergsKernel    k;
  PetscErrorCode ierr;
  PetscMPIInt    size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(PetscOptionsClear(NULL));
  PetscCall(PetscOptionsInsertString(NULL, "-kernel_solver cholmod"));
  PetscCall(KergsKernelCreate(PETSC_COMM_WORLD, &k));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KergsKernelSetFromOptions(k);
  PetscCall(PetscPopErrorHandler());
  PetscCall(Check((PetscBool)(ierr == PETSC_ERR_ARG_INCOMP), "-kernel_solver cholmod on 2 ranks is an error", ierr, PETSC_ERR_ARG_INCOMP));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(PetscOptionsClear(NULL));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscMPIInt size;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(TestDepositWindow(PETSC_TRUE));
  PetscCall(TestDepositWindow(PETSC_FALSE));
  PetscCall(TestDeposit500());
  PetscCall(TestWedged());
  PetscCall(TestHexCrystal());
  PetscCall(TestNoKernel());
  PetscCall(TestCollinear("mumps"));
  if (size == 1) PetscCall(TestCollinear("cholmod"));
  PetscCall(TestFreePatch());
  PetscCall(TestGuidedWall());
  PetscCall(TestFrictionalRow());
  PetscCall(TestCholmodParallel());
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
