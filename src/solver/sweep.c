/* kergs sweep: one non-linear Gauss-Seidel sweep over a rank's contacts (Algorithm 2; docs/design.md: algorithms,
   parallel layout). The sweep reads W's block CSR arrays directly: one block row per contact, blocks W_alpha,beta of
   ncomp x ncomp (BAIJ, each block stored column by column; AIJ is the case ncomp = 1). Inside a rank it is Gauss-Seidel (contact alpha sees
   the impulses already updated in this sweep); across ranks it is Jacobi: the impulses of other ranks'
   contacts are scattered once per sweep into rghost and enter through Ao rghost, a correction kept for the few rows
   they couple to (the coupled rows) only, so that the sweep reads no more per contact than on one rank.
   W symmetric may be stored by its upper block triangle only (SBAIJ: W_alpha,beta for beta >= alpha), which halves
   the memory the sweep streams. Then, with the same Gauss-Seidel order, sum_{beta < alpha} W_alpha,beta r_beta(new)
   = sum_{beta < alpha} W_beta,alpha^T r_beta(new) is gathered in acc_alpha: once r_beta(new) is known, row beta
   (still in cache) adds W_beta,gamma^T r_beta(new) to acc_gamma for its stored gamma > beta. Across ranks, the
   off-process part B of a rank holds the columns of higher ranks only; the coupling with lower ranks is B^T r
   computed on those ranks and added back through the same scatter reversed.
   For Algorithm 6 (NLGS-Jac) the caller passes the extra right-hand side and the regularised diagonal
   blocks W_aa + Z_aa; both are used as given. */
#include <kergs/private/sweepimpl.h>

/* The block kernels are specialised by inlining with a constant number of components (1 or 2); the compiler's
   heuristics alone do not inline the sweep loop into its two call sites. */
#if PetscHasAttribute(always_inline)
#define KERGS_ALWAYS_INLINE __attribute__((always_inline))
#else
#define KERGS_ALWAYS_INLINE
#endif

PetscErrorCode KergsSweepCreate(MPI_Comm comm, KergsSweep *sweep)
{
  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(sweep));
  (*sweep)->comm = comm;
  PetscFunctionReturn(0);
}

/* The block CSR arrays of a local block of W (kept until KergsSweepReset): block row a holds the blocks
   [ia[a], ia[a+1]), block j has block column ja[j] and its bs*bs values at a + j*bs*bs. For BAIJ (blocked)
   the block-compressed row structure and the value array (column-major blocks); for AIJ the plain CSR,
   not inode-compressed. */
static PetscErrorCode GetBlockCSR(Mat A, PetscBool blocked, PetscBool upper, const PetscInt **ia, const PetscInt **ja,
                                  const PetscScalar **a)
{
  PetscInt     nrow;
  PetscBool    done;
  PetscScalar *v;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, blocked, &nrow, ia, ja, &done));
  PetscCheck(done, PetscObjectComm((PetscObject)A), PETSC_ERR_SUP, "sweep.c: MatGetRowIJ cannot give the CSR arrays of W's local block");
  if (upper) {
    PetscCall(MatSeqSBAIJGetArray(A, &v));
    *a = v;
  } else if (blocked) {
    PetscCall(MatSeqBAIJGetArray(A, &v));
    *a = v;
  } else
    PetscCall(MatSeqAIJGetArrayRead(A, a));
  PetscFunctionReturn(0);
}

static PetscErrorCode RestoreBlockCSR(Mat A, PetscBool blocked, PetscBool upper, const PetscInt **ia, const PetscInt **ja,
                                      const PetscScalar **a)
{
  PetscInt     nrow;
  PetscBool    done;
  PetscScalar *v = (PetscScalar *)*a;

  PetscFunctionBeginUser;
  if (*a) {
    if (upper)
      PetscCall(MatSeqSBAIJRestoreArray(A, &v));
    else if (blocked)
      PetscCall(MatSeqBAIJRestoreArray(A, &v));
    else
      PetscCall(MatSeqAIJRestoreArrayRead(A, a));
  }
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, blocked, &nrow, ia, ja, &done));
  *a = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepReset(KergsSweep s)
{
  PetscFunctionBeginUser;
  if (s->Ad && s->ai) PetscCall(RestoreBlockCSR(s->Ad, s->blocked, s->upper, &s->ai, &s->aj, &s->aa));
  if (s->Ao && s->bi) PetscCall(RestoreBlockCSR(s->Ao, s->blocked, PETSC_FALSE, &s->bi, &s->bj, &s->ba));
  PetscCall(PetscFree(s->ubi));
  PetscCall(PetscFree(s->ubj));
  PetscCall(PetscFree(s->uba));
  PetscCall(PetscFree(s->acc));
  PetscCall(VecDestroy(&s->blower));
  PetscCall(VecDestroy(&s->ylower));
  PetscCall(VecScatterDestroy(&s->lower_scatter));
  s->ai = s->aj = s->bi = s->bj = NULL;
  s->aa = s->ba = NULL;
  s->Ad = s->Ao = NULL;
  PetscCall(VecScatterDestroy(&s->ghost_scatter));
  PetscCall(VecDestroy(&s->rghost));
  PetscCall(PetscFree(s->Wdiag));
  PetscCall(PetscFree(s->orows));
  PetscCall(PetscFree(s->corr));
  s->norows = 0;
  PetscCall(PetscFree(s->dsplit));
  PetscCall(MatDestroy(&s->W));
  s->mu      = NULL;
  s->active  = NULL;
  s->n       = 0;
  s->ncomp   = 0;
  s->blocked = PETSC_FALSE;
  s->upper   = PETSC_FALSE;
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

/* W_aa of local contact a, row-major as the law takes it, into w (ncomp*ncomp). With upper storage W_aa is the first
   block of row a (checked at set-up) and is read there, stored column by column (entry (c, e) at c + e*nc); with whole
   storage from the copy Wdiag made at set-up. Inlined with a constant nc. */
static inline KERGS_ALWAYS_INLINE void DiagonalBlock(const PetscInt nc, PetscInt a, const PetscInt *ai, const PetscScalar *aa,
                                                     const PetscReal *Wdiag, PetscReal *w)
{
  PetscInt c, e;

  if (Wdiag)
    for (c = 0; c < nc * nc; c++) w[c] = Wdiag[a * nc * nc + c];
  else
    for (c = 0; c < nc; c++)
      for (e = 0; e < nc; e++) w[c * nc + e] = PetscRealPart(aa[ai[a] * nc * nc + e * nc + c]);
}

PetscErrorCode KergsSweepGetDiagonalBlocks(KergsSweep s, PetscReal *blocks)
{
  PetscFunctionBeginUser;
  PetscCheck(s->W, s->comm, PETSC_ERR_ORDER, "KergsSweepGetDiagonalBlocks: call KergsSweepSetUp first");
  for (PetscInt a = 0; a < s->n; a++) DiagonalBlock(s->ncomp, a, s->ai, s->aa, s->Wdiag, blocks + a * s->ncomp * s->ncomp);
  PetscFunctionReturn(0);
}

/* Locate the own block W_aa in each sorted block row. Upper storage: it must be the first block of its row, where
   the sweep reads it. Whole storage: the sweep skips the blocks [dsplit[2a], dsplit[2a+1]) of row a (none if W_aa
   is not stored), and W_aa is copied row-major into Wdiag (BAIJ stores a block column by column: entry (c, e) at
   c + e*nc). */
static PetscErrorCode LocateDiagonalBlocks(KergsSweep s)
{
  const PetscInt nc = s->ncomp, bs2 = nc * nc;
  PetscInt       a, c, e, j;

  PetscFunctionBeginUser;
  if (s->upper) {
    for (a = 0; a < s->n; a++) {
      j = s->ai[a];
      PetscCheck(j < s->ai[a + 1] && s->aj[j] == a, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
                 "KergsSweepSetUp: W's diagonal block of local contact %" PetscInt_FMT " is not stored", a);
    }
    PetscFunctionReturn(0);
  }
  PetscCall(PetscCalloc1(s->n * bs2, &s->Wdiag));
  PetscCall(PetscMalloc1(2 * s->n, &s->dsplit));
  for (a = 0; a < s->n; a++) {
    for (j = s->ai[a]; j < s->ai[a + 1] && s->aj[j] < a; j++) {
    }
    s->dsplit[2 * a] = j;
    if (j < s->ai[a + 1] && s->aj[j] == a) {
      for (c = 0; c < nc; c++)
        for (e = 0; e < nc; e++) s->Wdiag[a * bs2 + c * nc + e] = PetscRealPart(s->aa[j * bs2 + e * nc + c]);
      j++;
    }
    s->dsplit[2 * a + 1] = j;
  }
  PetscFunctionReturn(0);
}

/* Scatter from the global r to the sequential rghost whose block j (ncomp entries) is the global block column
   colmap[j] (an off-process contact, nghost of them), so that the off-process part's block column j reads
   rghost[j*ncomp .. j*ncomp+ncomp). */
static PetscErrorCode CreateGhostScatter(KergsSweep s, PetscInt nghost, const PetscInt *colmap)
{
  IS  is;
  Vec x;

  PetscFunctionBeginUser;
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, nghost * s->ncomp, &s->rghost));
  PetscCall(ISCreateBlock(PETSC_COMM_SELF, s->ncomp, nghost, colmap, PETSC_COPY_VALUES, &is));
  PetscCall(MatCreateVecs(s->W, &x, NULL));
  PetscCall(VecScatterCreate(x, is, s->rghost, NULL, &s->ghost_scatter));
  if (s->upper) {
    PetscCall(VecDuplicate(x, &s->blower));
    PetscCall(VecDuplicate(s->rghost, &s->ylower));
    PetscCall(VecScatterCopy(s->ghost_scatter, &s->lower_scatter)); /* one scatter holds one message in flight */
  }
  PetscCall(VecDestroy(&x));
  PetscCall(ISDestroy(&is));
  PetscFunctionReturn(0);
}

/* W's storage: (seq|mpi)sbaij (upper block triangle) or (seq|mpi)baij with block size ncomp, or (seq|mpi)aij when
   ncomp = 1 (a block is one entry). */
static PetscErrorCode CheckStorage(KergsSweep s, Mat W, PetscInt ncomp, PetscBool *ismpi, PetscBool *blocked, PetscBool *upper)
{
  MatType   type;
  PetscBool seqaij, mpiaij, seqbaij, mpibaij, seqsbaij, mpisbaij;
  PetscInt  bs;

  PetscFunctionBeginUser;
  PetscCall(MatGetType(W, &type));
  PetscCall(PetscStrbeginswith(type, MATSEQAIJ, &seqaij));
  PetscCall(PetscStrbeginswith(type, MATMPIAIJ, &mpiaij));
  PetscCall(PetscStrbeginswith(type, MATSEQBAIJ, &seqbaij));
  PetscCall(PetscStrbeginswith(type, MATMPIBAIJ, &mpibaij));
  PetscCall(PetscStrbeginswith(type, MATSEQSBAIJ, &seqsbaij));
  PetscCall(PetscStrbeginswith(type, MATMPISBAIJ, &mpisbaij));
  PetscCall(MatGetBlockSize(W, &bs));
  *ismpi   = (PetscBool)(mpiaij || mpibaij || mpisbaij);
  *upper   = (PetscBool)(seqsbaij || mpisbaij);
  *blocked = (PetscBool)(seqbaij || mpibaij || *upper);
  PetscCheck(*blocked || seqaij || mpiaij, s->comm, PETSC_ERR_SUP,
             "KergsSweepSetUp: W has type %s; the sweep needs an assembled (seq|mpi)(s)baij or (seq|mpi)aij matrix", type);
  PetscCheck(*blocked ? bs == ncomp : ncomp == 1, s->comm, PETSC_ERR_SUP,
             "KergsSweepSetUp: W of type %s, block size %" PetscInt_FMT ", for %" PetscInt_FMT
             " components per contact: the sweep needs (s)baij with block size ncomp (aij for one component)",
             type, bs, ncomp);
  PetscFunctionReturn(0);
}

/* Values of the stored blocks of W's off-process part in the local scalar row `row` (block row a, component c),
   columns >= cend (upper storage: the higher ranks' contacts), into the block CSR copy: the k-th such column is
   entry (c, col % nc) of block ubi[a] + k / nc (a stored block holds nc entries in each of its rows), block column
   col / nc (global for now). */
static PetscErrorCode CopyOffProcessRow(KergsSweep s, PetscInt row, PetscInt a, PetscInt c, PetscInt cend)
{
  const PetscInt     nc = s->ncomp;
  PetscInt           ncols, k, j, pos;
  const PetscInt    *cols;
  const PetscScalar *vals;

  PetscFunctionBeginUser;
  PetscCall(MatGetRow(s->W, row, &ncols, &cols, &vals));
  for (k = 0; k < ncols && cols[k] < cend; k++) {
  }
  PetscCheck((ncols - k) == nc * (s->ubi[a + 1] - s->ubi[a]), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "KergsSweepSetUp: W's row %" PetscInt_FMT " is not made of whole blocks", row);
  for (j = 0; k < ncols; k++, j++) {
    pos                                             = s->ubi[a] + j / nc;
    s->ubj[pos]                                     = cols[k] / nc;
    s->uba[pos * nc * nc + (cols[k] % nc) * nc + c] = vals[k];
  }
  PetscCall(MatRestoreRow(s->W, row, &ncols, &cols, &vals));
  PetscFunctionReturn(0);
}

/* Upper storage on several ranks: the off-process part of an MPISBAIJ W (block columns right of this rank's range)
   is private to PETSc, so it is copied through MatGetRow (upper rows) into block CSR (ubi, ubj, uba), block column j
   being the contact colmap[j] (sorted, nghost of them; PetscFree). It is the coupling with higher ranks only. */
static PetscErrorCode CopyOffProcessUpper(KergsSweep s, PetscInt *nghost, PetscInt **colmap)
{
  const PetscInt nc = s->ncomp;
  PetscInt       rstart, cend, ncols, a, c, j, nb;

  PetscFunctionBeginUser;
  PetscCall(MatGetOwnershipRange(s->W, &rstart, &cend));
  PetscCall(PetscCalloc1(s->n + 1, &s->ubi));
  PetscCall(MatGetRowUpperTriangular(s->W));
  for (a = 0; a < s->n; a++) { /* block counts from each block row's first row */
    const PetscInt *cols;
    PetscCall(MatGetRow(s->W, rstart + a * nc, &ncols, &cols, NULL));
    for (j = 0; j < ncols; j++) s->ubi[a + 1] += cols[j] >= cend;
    PetscCall(MatRestoreRow(s->W, rstart + a * nc, &ncols, &cols, NULL));
    s->ubi[a + 1] = s->ubi[a] + s->ubi[a + 1] / nc;
  }
  nb = s->ubi[s->n];
  PetscCall(PetscMalloc1(nb + 1, &s->ubj));
  PetscCall(PetscMalloc1(nb * nc * nc + 1, &s->uba));
  for (a = 0; a < s->n; a++)
    for (c = 0; c < nc; c++) PetscCall(CopyOffProcessRow(s, rstart + a * nc + c, a, c, cend));
  PetscCall(MatRestoreRowUpperTriangular(s->W));
  /* global block columns -> positions in the sorted list of ghost contacts */
  PetscCall(PetscMalloc1(nb + 1, colmap));
  PetscCall(PetscArraycpy(*colmap, s->ubj, nb));
  *nghost = nb;
  PetscCall(PetscSortRemoveDupsInt(nghost, *colmap));
  for (j = 0; j < nb; j++) PetscCall(PetscFindInt(s->ubj[j], *nghost, *colmap, &s->ubj[j]));
  s->bi = s->ubi;
  s->bj = s->ubj;
  s->ba = s->uba;
  PetscFunctionReturn(0);
}

/* The local diagonal block and the off-process part (with its ghost scatter) of a distributed W. */
static PetscErrorCode SetUpParts(KergsSweep s)
{
  const PetscInt *colmap;
  PetscInt       *ucolmap, nghost, ncol;

  PetscFunctionBeginUser;
  if (s->upper) {
    PetscCall(MatGetDiagonalBlock(s->W, &s->Ad));
    PetscCall(CopyOffProcessUpper(s, &nghost, &ucolmap));
    PetscCall(CreateGhostScatter(s, nghost, ucolmap));
    PetscCall(PetscFree(ucolmap));
    PetscFunctionReturn(0);
  }
  if (s->blocked)
    PetscCall(MatMPIBAIJGetSeqBAIJ(s->W, &s->Ad, &s->Ao, &colmap));
  else
    PetscCall(MatMPIAIJGetSeqAIJ(s->W, &s->Ad, &s->Ao, &colmap));
  PetscCall(GetBlockCSR(s->Ao, s->blocked, PETSC_FALSE, &s->bi, &s->bj, &s->ba));
  PetscCall(MatGetSize(s->Ao, NULL, &ncol));
  PetscCall(CreateGhostScatter(s, ncol / s->ncomp, colmap));
  PetscFunctionReturn(0);
}

/* The rows with an off-process coupling (coupled rows, sorted): a block of B, or a contribution from a lower rank
   (upper storage: found by scattering ones back), and their corrections corr. */
static PetscErrorCode FindCoupledRows(KergsSweep s)
{
  const PetscInt nc = s->ncomp;
  PetscBool     *coupled;
  PetscInt       a, c;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(s->n + 1, &coupled));
  for (a = 0; a < s->n; a++) coupled[a] = (PetscBool)(s->bi[a + 1] > s->bi[a]);
  if (s->upper) {
    const PetscScalar *bl;
    PetscCall(VecSet(s->blower, 0.0));
    PetscCall(VecSet(s->ylower, 1.0));
    PetscCall(VecScatterBegin(s->lower_scatter, s->ylower, s->blower, ADD_VALUES, SCATTER_REVERSE));
    PetscCall(VecScatterEnd(s->lower_scatter, s->ylower, s->blower, ADD_VALUES, SCATTER_REVERSE));
    PetscCall(VecGetArrayRead(s->blower, &bl));
    for (a = 0; a < s->n; a++)
      for (c = 0; c < nc; c++) coupled[a] = (PetscBool)(coupled[a] || PetscRealPart(bl[a * nc + c]) != 0.0);
    PetscCall(VecRestoreArrayRead(s->blower, &bl));
    PetscCall(VecSet(s->blower, 0.0));
  }
  s->norows = 0;
  for (a = 0; a < s->n; a++) s->norows += coupled[a];
  PetscCall(PetscMalloc1(s->norows + 1, &s->orows));
  for (a = 0, s->norows = 0; a < s->n; a++)
    if (coupled[a]) s->orows[s->norows++] = a;
  PetscCall(PetscFree(coupled));
  PetscCall(PetscMalloc1(s->norows * nc + 1, &s->corr));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepSetUp(KergsSweep s, Mat W, PetscInt ncomp, const PetscReal *mu, const PetscBool *active)
{
  PetscBool ismpi = PETSC_FALSE, blocked = PETSC_FALSE, upper = PETSC_FALSE;
  PetscInt  m, mcol, rstart, cstart;

  PetscFunctionBeginUser;
  PetscCall(KergsSweepReset(s));
  PetscCheck(ncomp >= 1 && ncomp <= KERGS_MAXCOMP, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "KergsSweepSetUp: %" PetscInt_FMT " components per contact, expected 1 to %d", ncomp, KERGS_MAXCOMP);
  PetscCall(CheckStorage(s, W, ncomp, &ismpi, &blocked, &upper));
  PetscCall(MatGetLocalSize(W, &m, &mcol));
  PetscCall(MatGetOwnershipRange(W, &rstart, NULL));
  PetscCall(MatGetOwnershipRangeColumn(W, &cstart, NULL));
  PetscCheck(m == mcol && rstart == cstart, s->comm, PETSC_ERR_ARG_SIZ,
             "KergsSweepSetUp: W's local rows and columns must be the same contact components");
  PetscCheck(m % ncomp == 0, s->comm, PETSC_ERR_ARG_SIZ,
             "KergsSweepSetUp: %" PetscInt_FMT " local rows of W is not a multiple of %" PetscInt_FMT " components", m, ncomp);

  PetscCall(PetscObjectReference((PetscObject)W));
  s->W       = W;
  s->ncomp   = ncomp;
  s->n       = m / ncomp;
  s->blocked = blocked;
  s->upper   = upper;
  s->mu      = (PetscReal *)mu;
  s->active  = (PetscBool *)active;
  if (ismpi)
    PetscCall(SetUpParts(s));
  else
    s->Ad = W;
  PetscCall(GetBlockCSR(s->Ad, blocked, upper, &s->ai, &s->aj, &s->aa));
  if (s->ghost_scatter) PetscCall(FindCoupledRows(s)); /* none on one rank: no off-process part */
  if (upper) PetscCall(PetscMalloc1(m + 1, &s->acc));
  PetscCall(LocateDiagonalBlocks(s));
  s->compute_seconds = 0;
  PetscFunctionReturn(0);
}

/* b[c] += sum over the blocks [j0, j1) of a block row of W_block(c, e) x[ja[j]*nc + e], each block stored
   column by column (entry (c, e) at c + e*nc). Inlined with a constant nc. */
static inline KERGS_ALWAYS_INLINE void BlocksTimesX(const PetscInt nc, const PetscInt *ja, const PetscScalar *va, PetscInt j0, PetscInt j1,
                                                    const PetscScalar *x, PetscReal *b)
{
  PetscInt c, e, j;

  for (j = j0; j < j1; j++) {
    const PetscScalar *v  = va + j * nc * nc;
    const PetscScalar *xb = x + ja[j] * nc;
    for (e = 0; e < nc; e++)
      for (c = 0; c < nc; c++) b[c] += PetscRealPart(v[e * nc + c] * xb[e]);
  }
}

/* corr_k = (Ao rghost)_a + lower_a at the k-th coupled row a: the contributions of other ranks' contacts, frozen
   for the sweep (Jacobi across ranks); lower (NULL without upper storage) is the lower ranks' share. */
static inline KERGS_ALWAYS_INLINE void OffProcessProduct(const PetscInt nc, PetscInt nrows, const PetscInt *rows, const PetscInt *bi,
                                                         const PetscInt *bj, const PetscScalar *ba, const PetscScalar *rg,
                                                         const PetscScalar *lower, PetscReal *corr)
{
  PetscInt k, a, c;

  for (k = 0; k < nrows; k++) {
    PetscReal t[KERGS_MAXCOMP] = {0.0};
    a                          = rows[k];
    BlocksTimesX(nc, bj, ba, bi[a], bi[a + 1], rg, t);
    for (c = 0; c < nc; c++) corr[k * nc + c] = t[c] + (lower ? PetscRealPart(lower[a * nc + c]) : 0.0);
  }
}

/* y[ja[j]*nc + e] += sum_c W_block(c, e) x[c] over the blocks [j0, j1) of a block row: the transposed blocks
   W_block^T applied to x, the ncomp values of the row's contact. Inlined with a constant nc. */
static inline KERGS_ALWAYS_INLINE void BlocksTransposeTimesX(const PetscInt nc, const PetscInt *ja, const PetscScalar *va, PetscInt j0,
                                                             PetscInt j1, const PetscReal *x, PetscReal *y)
{
  PetscInt c, e, j;

  for (j = j0; j < j1; j++) {
    const PetscScalar *v  = va + j * nc * nc;
    PetscReal         *yb = y + ja[j] * nc;
    for (e = 0; e < nc; e++)
      for (c = 0; c < nc; c++) yb[e] += PetscRealPart(v[e * nc + c]) * x[c];
  }
}

/* y = B^T r over the coupled rows (upper storage): the coupling of this rank's contacts with the higher ranks'
   ones seen from those ranks, y ordered as B's block columns (rghost). */
static inline KERGS_ALWAYS_INLINE void OffProcessTransposeProduct(const PetscInt nc, PetscInt nrows, const PetscInt *rows,
                                                                  const PetscInt *bi, const PetscInt *bj, const PetscScalar *ba,
                                                                  const PetscScalar *r, PetscReal *y)
{
  PetscInt k, a, c;

  for (k = 0; k < nrows; k++) {
    PetscReal x[KERGS_MAXCOMP];
    a = rows[k];
    for (c = 0; c < nc; c++) x[c] = PetscRealPart(r[a * nc + c]);
    BlocksTransposeTimesX(nc, bj, ba, bi[a], bi[a + 1], x, y);
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

/* The Gauss-Seidel loop over the rank's contacts (Algorithm 2): for contact a,
     b_a = vd_a + corr_a + extra_a + sum_{local beta != a} W_a,beta r_beta   (latest r),
   corr_a the other ranks' contributions, frozen for the sweep, at the coupled rows orows (several ranks; found by a
   cursor that follows a: the sweep reads nothing more at the other rows),
   then the exact law with the block Wlaw_a, r_a updated in place. Block row a of W is contact a: its blocks
   before and after the own block, [ai[a], ds[2a]) and [ds[2a+1], ai[a+1]), give the sum. With upper storage
   (acc not NULL, zero on entry; ds not used) the row holds W_aa first, then beta > a only (r_beta not yet updated: the old values, as
   Gauss-Seidel wants), and acc_a = sum_{beta < a} W_beta,a^T r_beta(new) = sum_{beta < a} W_a,beta r_beta(new)
   completes the sum; once r_a(new) is known the same row adds W_a,beta^T r_a(new) to acc_beta. nc is 1 or 2; the
   function is inlined with a constant nc so that the small loops over components unroll. */
static inline KERGS_ALWAYS_INLINE void SweepContacts(const PetscInt nc, PetscInt n, const PetscInt *ai, const PetscInt *aj,
                                                     const PetscScalar *aa, const PetscInt *ds, const PetscScalar *vd, PetscInt norows,
                                                     const PetscInt *orows, const PetscReal *corr, const PetscReal *extra,
                                                     const PetscReal *Wlaw, const PetscReal *Wdiag, const PetscReal *mu,
                                                     const PetscBool *active, PetscScalar *r, PetscReal *acc, SweepSums *sums)
{
  PetscReal b[KERGS_MAXCOMP], rnew[KERGS_MAXCOMP], dr[KERGS_MAXCOMP], w[KERGS_MAXCOMP * KERGS_MAXCOMP], dWd, rWr;
  PetscInt  a, c, e, i, k = 0;

  for (a = 0; a < n; a++) {
    const PetscBool  act  = active ? active[a] : PETSC_TRUE;
    const PetscInt   jlow = acc ? ai[a] : ds[2 * a], jup = acc ? ai[a] + 1 : ds[2 * a + 1]; /* upper: W_aa first */
    const PetscReal *co = NULL;

    if (k < norows && orows[k] == a) co = corr + nc * k++;
    if (!act) { /* the law gives r_a = 0: nothing changes, and nothing is measured, once it is 0 */
      PetscBool zero = PETSC_TRUE;
      for (c = 0; c < nc; c++) zero = (PetscBool)(zero && r[a * nc + c] == 0.0);
      if (zero) continue;
    } else {
      PetscReal t[KERGS_MAXCOMP] = {0.0};
      if (acc) /* upper storage: the blocks before the own one, summed in the same order as whole storage does */
        for (c = 0; c < nc; c++) t[c] = acc[a * nc + c];
      BlocksTimesX(nc, aj, aa, ai[a], jlow, r, t);
      BlocksTimesX(nc, aj, aa, jup, ai[a + 1], r, t);
      for (c = 0; c < nc; c++) {
        i    = a * nc + c;
        b[c] = PetscRealPart(vd[i]) + (co ? co[c] : 0.0) + t[c];
        if (extra) b[c] += extra[i];
      }
    }
    DiagonalBlock(nc, a, ai, aa, Wdiag, w);
    KergsLawSolve(nc, Wlaw ? Wlaw + a * nc * nc : w, b, mu ? mu[a] : 0.0, act, rnew);
    /* W_aa-weighted measures of the change (nlgs.h) */
    dWd = rWr = 0.0;
    for (c = 0; c < nc; c++) {
      dr[c]         = rnew[c] - r[a * nc + c];
      r[a * nc + c] = rnew[c];
    }
    for (c = 0; c < nc; c++)
      for (e = 0; e < nc; e++) {
        dWd += dr[c] * w[c * nc + e] * dr[e];
        rWr += rnew[c] * w[c * nc + e] * rnew[e];
      }
    if (acc) {
      PetscBool zero = PETSC_TRUE;
      for (c = 0; c < nc; c++) zero = (PetscBool)(zero && rnew[c] == 0.0);
      if (!zero) BlocksTransposeTimesX(nc, aj, aa, jup, ai[a + 1], rnew, acc);
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

/* Upper storage: the lower ranks' share of the coupling is (B^T r) computed on each of them and added back through the
   ghost scatter reversed (r is the impulse at the start of the sweep, as for the forward part: Jacobi across ranks).
   Started before the forward scatter so that both messages are in flight together. The reverse scatter adds only into
   the rows that the lower ranks couple to (coupled rows), the only entries of blower zeroed and read. */
static PetscErrorCode BeginLowerRanksCoupling(KergsSweep s, Vec r)
{
  const PetscScalar *rl;
  PetscScalar       *y, *bl;
  PetscLogDouble     t0, t1;

  PetscFunctionBeginUser;
  PetscCall(VecSet(s->ylower, 0.0));
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArray(s->ylower, &y));
  PetscCall(PetscTime(&t0));
  if (s->ncomp == 2)
    OffProcessTransposeProduct(2, s->norows, s->orows, s->bi, s->bj, s->ba, rl, y);
  else
    OffProcessTransposeProduct(1, s->norows, s->orows, s->bi, s->bj, s->ba, rl, y);
  PetscCall(PetscTime(&t1));
  s->compute_seconds += t1 - t0;
  PetscCall(VecRestoreArray(s->ylower, &y));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(VecGetArray(s->blower, &bl));
  for (PetscInt k = 0; k < s->norows; k++)
    for (PetscInt c = 0; c < s->ncomp; c++) bl[s->orows[k] * s->ncomp + c] = 0.0;
  PetscCall(VecRestoreArray(s->blower, &bl));
  PetscCall(VecScatterBegin(s->lower_scatter, s->ylower, s->blower, ADD_VALUES, SCATTER_REVERSE));
  PetscFunctionReturn(0);
}

/* Several ranks: the other ranks' contributions at the coupled rows, corr. */
static PetscErrorCode OffProcessCorrection(KergsSweep s, Vec r)
{
  const PetscInt     nc = s->ncomp;
  const PetscScalar *rg, *bl = NULL;
  PetscLogDouble     t0, t1;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_Exchange, 0, 0, 0, 0));
  if (s->upper) PetscCall(BeginLowerRanksCoupling(s, r));
  PetscCall(VecScatterBegin(s->ghost_scatter, r, s->rghost, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(s->ghost_scatter, r, s->rghost, INSERT_VALUES, SCATTER_FORWARD));
  if (s->upper) PetscCall(VecScatterEnd(s->lower_scatter, s->ylower, s->blower, ADD_VALUES, SCATTER_REVERSE));
  PetscCall(PetscLogEventEnd(KERGS_Exchange, 0, 0, 0, 0));
  PetscCall(VecGetArrayRead(s->rghost, &rg));
  if (s->upper) PetscCall(VecGetArrayRead(s->blower, &bl));
  PetscCall(PetscTime(&t0));
  if (nc == 2)
    OffProcessProduct(2, s->norows, s->orows, s->bi, s->bj, s->ba, rg, bl, s->corr);
  else
    OffProcessProduct(1, s->norows, s->orows, s->bi, s->bj, s->ba, rg, bl, s->corr);
  PetscCall(PetscTime(&t1));
  s->compute_seconds += t1 - t0;
  if (s->upper) PetscCall(VecRestoreArrayRead(s->blower, &bl));
  PetscCall(VecRestoreArrayRead(s->rghost, &rg));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepRun(KergsSweep s, Vec r, Vec vd, const PetscReal *extra, const PetscReal *Wdiag_override,
                             KergsSweepMeasures *measures)
{
  const PetscInt     nc = s->ncomp, m = s->n * s->ncomp;
  PetscInt           mr, mv;
  PetscScalar       *rl;
  const PetscScalar *vdl;
  SweepSums          loc = {0, 0, 0, 0, 0}, glob;
  PetscReal          sums[4], maxd;
  PetscLogDouble     t0, t1;

  PetscFunctionBeginUser;
  PetscCheck(s->W, s->comm, PETSC_ERR_ORDER, "KergsSweepRun: call KergsSweepSetUp first");
  PetscCall(VecGetLocalSize(r, &mr));
  PetscCall(VecGetLocalSize(vd, &mv));
  PetscCheck(mr == m && mv == m, s->comm, PETSC_ERR_ARG_SIZ,
             "KergsSweepRun: r and vd need %" PetscInt_FMT " local entries (have %" PetscInt_FMT ", %" PetscInt_FMT ")", m, mr, mv);
  PetscCall(PetscLogEventBegin(KERGS_Sweep, 0, 0, 0, 0));
  if (s->ghost_scatter) PetscCall(OffProcessCorrection(s, r));
  if (s->acc) PetscCall(PetscArrayzero(s->acc, m));
  PetscCall(VecGetArray(r, &rl));
  PetscCall(VecGetArrayRead(vd, &vdl));
  PetscCall(PetscTime(&t0));
  if (nc == 2)
    SweepContacts(2, s->n, s->ai, s->aj, s->aa, s->dsplit, vdl, s->norows, s->orows, s->corr, extra, Wdiag_override, s->Wdiag, s->mu,
                  s->active, rl, s->acc, &loc);
  else
    SweepContacts(1, s->n, s->ai, s->aj, s->aa, s->dsplit, vdl, s->norows, s->orows, s->corr, extra, Wdiag_override, s->Wdiag, s->mu,
                  s->active, rl, s->acc, &loc);
  PetscCall(PetscTime(&t1));
  s->compute_seconds += t1 - t0;
  PetscCall(VecRestoreArrayRead(vd, &vdl));
  PetscCall(VecRestoreArray(r, &rl));
  /* upper storage: each stored off-diagonal block is applied twice (as itself and transposed) */
  PetscCall(PetscLogFlops(2.0 * nc * nc * ((s->upper ? 2 : 1) * (s->ai[s->n] + (s->bi ? s->bi[s->n] : 0)))));

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

PetscErrorCode KergsSweepSetGapVelocities(KergsSweep s, const PetscReal *gapvel)
{
  PetscFunctionBeginUser;
  s->gapvel = gapvel;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepResiduals(KergsSweep s, Vec r, Vec vd, Vec v, KergsResiduals *res)
{
  const PetscInt     nc = s->ncomp;
  const PetscScalar *rl, *vl, *vdl;
  PetscReal          sums[3] = {0.0, 0.0, 0.0}, maxes[2] = {0.0, 0.0};
  PetscInt           a, c;

  PetscFunctionBeginUser;
  PetscCheck(s->W, s->comm, PETSC_ERR_ORDER, "KergsSweepResiduals: call KergsSweepSetUp first");
  PetscCall(MatMultAdd(s->W, r, vd, v));
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(v, &vl));
  PetscCall(VecGetArrayRead(vd, &vdl));
  for (a = 0; a < s->n; a++) {
    const PetscBool active = s->active ? s->active[a] : PETSC_TRUE;
    PetscReal       w[KERGS_MAXCOMP * KERGS_MAXCOMP], e[KERGS_MAXCOMP], rho, e2 = 0.0, q2 = 0.0, wr2 = 0.0;
    /* rho = 1 / W_aa,nn turns the velocity into an impulse (law.h) */
    DiagonalBlock(nc, a, s->ai, s->aa, s->Wdiag, w);
    rho = w[0] > 0 ? 1.0 / w[0] : 1.0;
    KergsLawNaturalMap(nc, rl + a * nc, vl + a * nc, s->mu ? s->mu[a] : 0.0, rho, active, e);
    for (c = 0; c < nc; c++) {
      e2 += e[c] * e[c];
      sums[1] += rl[a * nc + c] * rl[a * nc + c];
      sums[2] += PetscSqr(PetscRealPart(rl[a * nc + c]) - e[c]); /* |proj_K(r - rho v~)|^2 */
      q2 += PetscSqr(PetscRealPart(vdl[a * nc + c]) - (c == 0 && s->gapvel ? s->gapvel[a] : 0.0));
      wr2 += PetscSqr(PetscRealPart(vl[a * nc + c] - vdl[a * nc + c]));
    }
    sums[0] += e2;
    /* the velocity scale: the largest free velocity, or velocity change, of an active contact */
    if (active) maxes[1] = PetscMax(maxes[1], PetscSqrtReal(PetscMax(q2, wr2)));
    maxes[0] = PetscMax(maxes[0], PetscSqrtReal(e2) / rho);
  }
  PetscCall(VecRestoreArrayRead(vd, &vdl));
  PetscCall(VecRestoreArrayRead(v, &vl));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPIU_SUM, s->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, maxes, 2, MPIU_REAL, MPIU_MAX, s->comm));
  res->natural  = KergsLawNaturalResidualScaled(sums[0], sums[1], sums[2]);
  res->scale    = PetscSqrtReal(PetscMax(sums[1], sums[2]));
  res->velocity = maxes[1] > 0 ? maxes[0] / maxes[1] : maxes[0];
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepNaturalResidual(KergsSweep s, Vec r, Vec vd, Vec v, PetscReal *res)
{
  KergsResiduals all;

  PetscFunctionBeginUser;
  PetscCall(KergsSweepResiduals(s, r, vd, v, &all));
  *res = all.natural;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSweepGetComputeSeconds(KergsSweep s, PetscLogDouble *seconds)
{
  PetscFunctionBeginUser;
  *seconds = s->compute_seconds;
  PetscFunctionReturn(0);
}
