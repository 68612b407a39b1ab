/* kergs nlgs: one non-linear Gauss-Seidel sweep over a rank's contacts (Algorithm 2, DESIGN.md sections 4
   and 6). The sweep reads W's CSR arrays directly. Inside a rank it is Gauss-Seidel (contact alpha sees
   the impulses already updated in this sweep); across ranks it is Jacobi: the impulses of other ranks'
   contacts are scattered once per sweep into rghost and enter through boff = Ao rghost.
   For Algorithm 6 (NLGS-Jac) the caller passes the extra right-hand side and the regularised diagonal
   blocks W_aa + Z_aa; both are used as given. */
#include <kergs/nlgs.h>

PetscErrorCode KergsSweepCreate(MPI_Comm comm, KergsSweep *sweep)
{
  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(sweep));
  (*sweep)->comm = comm;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepReset(KergsSweep s)
{
  PetscInt  nrow;
  PetscBool done;

  PetscFunctionBeginUser;
  if (s->Ad) {
    if (s->aa) PetscCall(MatSeqAIJRestoreArrayRead(s->Ad, &s->aa));
    if (s->ai) PetscCall(MatRestoreRowIJ(s->Ad, 0, PETSC_FALSE, PETSC_FALSE, &nrow, &s->ai, &s->aj, &done));
  }
  if (s->Ao) {
    if (s->ba) PetscCall(MatSeqAIJRestoreArrayRead(s->Ao, &s->ba));
    if (s->bi) PetscCall(MatRestoreRowIJ(s->Ao, 0, PETSC_FALSE, PETSC_FALSE, &nrow, &s->bi, &s->bj, &done));
  }
  s->ai = s->aj = s->bi = s->bj = NULL;
  s->aa = s->ba = NULL;
  s->Ad = s->Ao = NULL;
  PetscCall(VecScatterDestroy(&s->ghost_scatter));
  PetscCall(VecDestroy(&s->rghost));
  PetscCall(PetscFree(s->Wdiag));
  PetscCall(PetscFree(s->boff));
  PetscCall(PetscFree(s->dsplit));
  PetscCall(MatDestroy(&s->W));
  s->mu     = NULL;
  s->active = NULL;
  s->n      = 0;
  s->ncomp  = 0;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepDestroy(KergsSweep *sweep)
{
  PetscFunctionBeginUser;
  if (!*sweep) PetscFunctionReturn(0);
  PetscCall(KergsSweepReset(*sweep));
  PetscCall(PetscFree(*sweep));
  PetscFunctionReturn(0);
}

/* Get the CSR arrays of a SeqAIJ block (kept until KergsSweepReset). */
static PetscErrorCode GetCSR(Mat A, const PetscInt **ia, const PetscInt **ja, const PetscScalar **a)
{
  PetscInt  nrow;
  PetscBool done;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &nrow, ia, ja, &done));
  if (!done) SETERRQ(PetscObjectComm((PetscObject)A), PETSC_ERR_SUP, "nlgs.c: MatGetRowIJ cannot give the CSR arrays of W's local block");
  PetscCall(MatSeqAIJGetArrayRead(A, a));
  PetscFunctionReturn(0);
}

/* Copy the diagonal blocks W_aa and locate, in each (sorted) row, the entries of the own block, which the
   sweep skips: row i = a*nc + c has its own block's entries at [dsplit[2i], dsplit[2i+1]). */
static PetscErrorCode ExtractDiagonalBlocks(KergsSweep s)
{
  const PetscInt nc = s->ncomp;
  PetscInt       a, c, i, j, col0;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(s->n * nc * nc, &s->Wdiag));
  PetscCall(PetscMalloc1(2 * s->n * nc, &s->dsplit));
  for (a = 0; a < s->n; a++) {
    col0 = a * nc;
    for (c = 0; c < nc; c++) {
      i = col0 + c;
      for (j = s->ai[i]; j < s->ai[i + 1] && s->aj[j] < col0; j++) { }
      s->dsplit[2 * i] = j;
      for (; j < s->ai[i + 1] && s->aj[j] < col0 + nc; j++) s->Wdiag[(a * nc + c) * nc + (s->aj[j] - col0)] = PetscRealPart(s->aa[j]);
      s->dsplit[2 * i + 1] = j;
    }
  }
  PetscFunctionReturn(0);
}

/* Scatter from the global r to the sequential rghost whose entry j is the global column colmap[j], so that
   Ao's column j reads rghost[j]. */
static PetscErrorCode CreateGhostScatter(KergsSweep s, const PetscInt *colmap)
{
  PetscInt nghost;
  IS       is;
  Vec      x;

  PetscFunctionBeginUser;
  PetscCall(MatGetSize(s->Ao, NULL, &nghost));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, nghost, &s->rghost));
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, nghost, colmap, PETSC_COPY_VALUES, &is));
  PetscCall(MatCreateVecs(s->W, &x, NULL));
  PetscCall(VecScatterCreate(x, is, s->rghost, NULL, &s->ghost_scatter));
  PetscCall(VecDestroy(&x));
  PetscCall(ISDestroy(&is));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepSetUp(KergsSweep s, Mat W, PetscInt ncomp, const PetscReal *mu, const PetscBool *active)
{
  MatType         type;
  PetscBool       isseq, ismpi;
  PetscInt        m, mcol, rstart, cstart;
  const PetscInt *colmap;

  PetscFunctionBeginUser;
  PetscCall(KergsSweepReset(s));
  if (ncomp < 1 || ncomp > KERGS_MAXCOMP)
    SETERRQ(s->comm, PETSC_ERR_ARG_OUTOFRANGE, "KergsSweepSetUp: %" PetscInt_FMT " components per contact, expected 1 to %d", ncomp, KERGS_MAXCOMP);
  PetscCall(MatGetType(W, &type));
  PetscCall(PetscStrbeginswith(type, MATSEQAIJ, &isseq));
  PetscCall(PetscStrbeginswith(type, MATMPIAIJ, &ismpi));
  if (!isseq && !ismpi) SETERRQ(s->comm, PETSC_ERR_SUP, "KergsSweepSetUp: W has type %s; the sweep needs an assembled seqaij or mpiaij matrix", type);
  PetscCall(MatGetLocalSize(W, &m, &mcol));
  PetscCall(MatGetOwnershipRange(W, &rstart, NULL));
  PetscCall(MatGetOwnershipRangeColumn(W, &cstart, NULL));
  if (m != mcol || rstart != cstart) SETERRQ(s->comm, PETSC_ERR_ARG_SIZ, "KergsSweepSetUp: W's local rows and columns must be the same contact components");
  if (m % ncomp) SETERRQ(s->comm, PETSC_ERR_ARG_SIZ, "KergsSweepSetUp: %" PetscInt_FMT " local rows of W is not a multiple of %" PetscInt_FMT " components", m, ncomp);

  PetscCall(PetscObjectReference((PetscObject)W));
  s->W      = W;
  s->ncomp  = ncomp;
  s->n      = m / ncomp;
  s->mu     = (PetscReal *)mu;
  s->active = (PetscBool *)active;
  if (ismpi) PetscCall(MatMPIAIJGetSeqAIJ(W, &s->Ad, &s->Ao, &colmap));
  else s->Ad = W;
  PetscCall(GetCSR(s->Ad, &s->ai, &s->aj, &s->aa));
  if (s->Ao) {
    PetscCall(GetCSR(s->Ao, &s->bi, &s->bj, &s->ba));
    PetscCall(CreateGhostScatter(s, colmap));
  }
  PetscCall(PetscCalloc1(m, &s->boff));
  PetscCall(ExtractDiagonalBlocks(s));
  PetscFunctionReturn(0);
}

/* boff = Ao rghost: the contributions of other ranks' contacts, frozen for the sweep (Jacobi across ranks). */
static void OffProcessProduct(PetscInt m, const PetscInt *bi, const PetscInt *bj, const PetscScalar *ba, const PetscScalar *rg, PetscReal *boff)
{
  PetscInt  i, j;
  PetscReal t;

  for (i = 0; i < m; i++) {
    t = 0.0;
    for (j = bi[i]; j < bi[i + 1]; j++) t += ba[j] * rg[bj[j]];
    boff[i] = t;
  }
}

/* Local quantities of one sweep, reduced over ranks into KergsSweepMeasures. */
typedef struct {
  PetscReal dWd;   /* sum dr^T Waa dr */
  PetscReal rWr;   /* sum r^T Waa r */
  PetscReal rootr; /* sum sqrt(r^T Waa r) */
  PetscReal count; /* contacts */
  PetscReal maxd;  /* max dr^T Waa dr */
} SweepSums;

/* Row i of W times r, skipping the row's own-block entries [d0, d1). */
static inline PetscReal RowTimesR(const PetscInt *aj, const PetscScalar *aa, PetscInt j0, PetscInt d0, PetscInt d1, PetscInt j1, const PetscReal *r)
{
  PetscReal t = 0.0;
  PetscInt  j;

  for (j = j0; j < d0; j++) t += aa[j] * r[aj[j]];
  for (j = d1; j < j1; j++) t += aa[j] * r[aj[j]];
  return t;
}

/* The Gauss-Seidel loop over the rank's contacts (Algorithm 2): for contact a,
     b_a = vd_a + extra_a + boff_a + sum_{local beta != a} W_a,beta r_beta   (latest r),
   then the exact law with the block Wlaw_a, r_a updated in place. nc is 1 or 2; the function is inlined
   with a constant nc so that the small loops over components unroll. */
static inline void SweepContacts(const PetscInt nc, PetscInt n, const PetscInt *ai, const PetscInt *aj, const PetscScalar *aa, const PetscInt *ds,
                                 const PetscScalar *vd, const PetscReal *boff, const PetscReal *extra, const PetscReal *Wlaw, const PetscReal *Wd,
                                 const PetscReal *mu, const PetscBool *active, PetscScalar *r, SweepSums *sums)
{
  PetscReal b[KERGS_MAXCOMP], rnew[KERGS_MAXCOMP], dr[KERGS_MAXCOMP], dWd, rWr;
  PetscInt  a, c, e, i;

  for (a = 0; a < n; a++) {
    const PetscBool act = active ? active[a] : PETSC_TRUE;
    const PetscReal *w  = Wd + a * nc * nc;

    if (act) {
      for (c = 0; c < nc; c++) {
        i    = a * nc + c;
        b[c] = vd[i] + boff[i] + RowTimesR(aj, aa, ai[i], ds[2 * i], ds[2 * i + 1], ai[i + 1], r);
        if (extra) b[c] += extra[i];
      }
    }
    KergsLawSolve(nc, Wlaw + a * nc * nc, b, mu ? mu[a] : 0.0, act, rnew);
    /* W_aa-weighted measures of the change (nlgs.h) */
    dWd = rWr = 0.0;
    for (c = 0; c < nc; c++) {
      dr[c] = rnew[c] - r[a * nc + c];
      r[a * nc + c] = rnew[c];
    }
    for (c = 0; c < nc; c++)
      for (e = 0; e < nc; e++) {
        dWd += dr[c] * w[c * nc + e] * dr[e];
        rWr += rnew[c] * w[c * nc + e] * rnew[e];
      }
    rWr = PetscMax(rWr, 0.0);
    sums->dWd += dWd;
    sums->rWr += rWr;
    sums->rootr += PetscSqrtReal(rWr);
    sums->maxd = PetscMax(sums->maxd, dWd);
  }
  sums->count += n;
}

/* quad and maxm from the global sums. A vanishing denominator (r = 0 after the sweep) gives 0 when nothing
   changed and 1 (a 100 % change) otherwise. */
static void MeasuresFromSums(const SweepSums *g, KergsSweepMeasures *m)
{
  const PetscReal mean = g->count > 0 ? g->rootr / g->count : 0.0;

  m->quad = g->rWr > 0 ? PetscSqrtReal(g->dWd / g->rWr) : (g->dWd > 0 ? 1.0 : 0.0);
  m->maxm = mean > 0 ? PetscSqrtReal(g->maxd) / mean : (g->maxd > 0 ? 1.0 : 0.0);
}

PetscErrorCode KergsSweepRun(KergsSweep s, Vec r, Vec vd, const PetscReal *extra, const PetscReal *Wdiag_override, KergsSweepMeasures *measures)
{
  const PetscInt     nc = s->ncomp, m = s->n * s->ncomp;
  PetscInt           mr, mv;
  PetscScalar       *rl;
  const PetscScalar *vdl, *rg;
  SweepSums          loc = {0, 0, 0, 0, 0}, glob;
  PetscReal          sums[4], maxd;

  PetscFunctionBeginUser;
  if (!s->W) SETERRQ(s->comm, PETSC_ERR_ORDER, "KergsSweepRun: call KergsSweepSetUp first");
  PetscCall(VecGetLocalSize(r, &mr));
  PetscCall(VecGetLocalSize(vd, &mv));
  if (mr != m || mv != m) SETERRQ(s->comm, PETSC_ERR_ARG_SIZ, "KergsSweepRun: r and vd need %" PetscInt_FMT " local entries (have %" PetscInt_FMT ", %" PetscInt_FMT ")", m, mr, mv);
  PetscCall(PetscLogEventBegin(KERGS_Sweep, 0, 0, 0, 0));
  if (s->ghost_scatter) {
    PetscCall(PetscLogEventBegin(KERGS_Exchange, 0, 0, 0, 0));
    PetscCall(VecScatterBegin(s->ghost_scatter, r, s->rghost, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(s->ghost_scatter, r, s->rghost, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(PetscLogEventEnd(KERGS_Exchange, 0, 0, 0, 0));
    PetscCall(VecGetArrayRead(s->rghost, &rg));
    OffProcessProduct(m, s->bi, s->bj, s->ba, rg, s->boff);
    PetscCall(VecRestoreArrayRead(s->rghost, &rg));
  }
  PetscCall(VecGetArray(r, &rl));
  PetscCall(VecGetArrayRead(vd, &vdl));
  if (nc == 2)
    SweepContacts(2, s->n, s->ai, s->aj, s->aa, s->dsplit, vdl, s->boff, extra, Wdiag_override ? Wdiag_override : s->Wdiag, s->Wdiag, s->mu, s->active, rl, &loc);
  else SweepContacts(1, s->n, s->ai, s->aj, s->aa, s->dsplit, vdl, s->boff, extra, Wdiag_override ? Wdiag_override : s->Wdiag, s->Wdiag, s->mu, s->active, rl, &loc);
  PetscCall(VecRestoreArrayRead(vd, &vdl));
  PetscCall(VecRestoreArray(r, &rl));
  PetscCall(PetscLogFlops(2.0 * (s->ai[m] + (s->bi ? s->bi[m] : 0))));

  sums[0] = loc.dWd;
  sums[1] = loc.rWr;
  sums[2] = loc.rootr;
  sums[3] = loc.count;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 4, MPIU_REAL, MPIU_SUM, s->comm));
  PetscCall(MPIU_Allreduce(&loc.maxd, &maxd, 1, MPIU_REAL, MPIU_MAX, s->comm));
  glob.dWd   = sums[0];
  glob.rWr   = sums[1];
  glob.rootr = sums[2];
  glob.count = sums[3];
  glob.maxd  = maxd;
  if (measures) MeasuresFromSums(&glob, measures);
  PetscCall(PetscLogEventEnd(KERGS_Sweep, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepNaturalResidual(KergsSweep s, Vec r, Vec vd, Vec v, PetscReal *res)
{
  const PetscInt     nc = s->ncomp;
  const PetscScalar *rl, *vl;
  PetscReal          sums[2] = {0.0, 0.0}, rho;
  PetscInt           a, c;

  PetscFunctionBeginUser;
  if (!s->W) SETERRQ(s->comm, PETSC_ERR_ORDER, "KergsSweepNaturalResidual: call KergsSweepSetUp first");
  PetscCall(MatMultAdd(s->W, r, vd, v));
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(v, &vl));
  for (a = 0; a < s->n; a++) {
    /* rho = 1 / W_aa,nn turns the velocity into an impulse (law.h) */
    rho = s->Wdiag[a * nc * nc] > 0 ? 1.0 / s->Wdiag[a * nc * nc] : 1.0;
    sums[0] += KergsLawNaturalResidual2(nc, rl + a * nc, vl + a * nc, s->mu ? s->mu[a] : 0.0, rho, s->active ? s->active[a] : PETSC_TRUE);
    for (c = 0; c < nc; c++) sums[1] += rl[a * nc + c] * rl[a * nc + c];
  }
  PetscCall(VecRestoreArrayRead(v, &vl));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 2, MPIU_REAL, MPIU_SUM, s->comm));
  /* relative to |r|; absolute when r = 0, so that the zero solution of an all-open problem gives 0 */
  *res = sums[1] > 0 ? PetscSqrtReal(sums[0]) / PetscMax(PetscSqrtReal(sums[1]), 1e-300) : PetscSqrtReal(sums[0]);
  PetscFunctionReturn(0);
}
