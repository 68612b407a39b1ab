/* Additive Schwarz for solver type "newton" (several ranks, newton_linear.c). First its subdomain solver: the subdomain's
   matrix, as PCASM extracts it (its rows in increasing order), copied block by block into the subdomain's own AMD order
   and factored there by PETSc's LU with the natural ordering, as one rank's J is (PresortContacts). PETSc's kernel for
   a permuted 2 x 2-block matrix copies and zeroes every block through a library call, its natural-ordering kernel
   does not. Handing PCASM the subdomain already in AMD order instead (PCASMSetLocalSubdomains, sorting off) made its
   extraction take the unsorted path of MatCreateSubMatrices: on the 100,000-disk strip, 2 ranks, the factorizations
   and triangular solves took 16 % and 22 % less time and the extractions 125 % more, no gain at all. The order, the
   permuted pattern and the map between the two value arrays are built once per step (the pattern is the step's);
   each factorization then costs one pass over the blocks more. Then its subdomain matrices, computed from W's (second
   half of this file). */
#include "newton.h"

#define SORTED_LU_NAME "LU with AMD, the subdomain copied into that order (natural-ordering kernel)"

typedef struct {
  KSP              factor;               /* LU, natural ordering, of P */
  Mat              P;                    /* the subdomain's matrix in its AMD order: P(i, j) = A(perm[i], perm[j]), by blocks */
  PetscInt        *perm;                 /* P's block row i is the subdomain's block row perm[i] */
  PetscInt        *src_block;            /* P's k-th stored block is the subdomain matrix's src_block[k]-th */
  PetscInt         nblocks, nstored, bs; /* block rows, stored blocks, block size */
  PetscInt64       id;                   /* the subdomain matrix P was built for, and its pattern */
  PetscObjectState pattern;
  Vec              xs, ys; /* right-hand side and solution in P's order */
} SortedLU;

static PetscErrorCode SortedLUClear(SortedLU *lu)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&lu->P));
  PetscCall(VecDestroy(&lu->xs));
  PetscCall(VecDestroy(&lu->ys));
  PetscCall(PetscFree2(lu->perm, lu->src_block));
  if (lu->factor) PetscCall(KSPReset(lu->factor));
  PetscFunctionReturn(0);
}

/* perm from AMD on A's block pattern, P = A permuted, and src_block: for each block row i of P (A's row perm[i]), the
   position in A's value array of each of its blocks, found through A's row marked by column. Rows are read by blocks
   for BAIJ; for AIJ (one component) as they are: asked to compress, MatGetRowIJ of AIJ merges rows of one pattern. */
static PetscErrorCode SortedLUBuild(SortedLU *lu, Mat A)
{
  IS              rows, cols, points;
  const PetscInt *idx, *ia, *ja, *ip, *jp;
  PetscInt        nrow, prow, *pos_in_row;
  PetscBool       done, pdone, blocked;

  PetscFunctionBeginUser;
  PetscCall(MatGetBlockSize(A, &lu->bs));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATSEQBAIJ, &blocked));
  PetscCheck(blocked || lu->bs == 1, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "newton: the sorted subdomain LU takes a BAIJ subdomain, or AIJ of block size 1 (got block size %" PetscInt_FMT
             "; -solver_pc_asm_sub_mat_type turns it off)",
             lu->bs);
  PetscCall(MatGetOrdering(A, MATORDERINGAMD, &rows, &cols));
  PetscCall(ISGetLocalSize(rows, &lu->nblocks));
  PetscCall(ISGetIndices(rows, &idx));
  PetscCall(ISCreateBlock(PETSC_COMM_SELF, lu->bs, lu->nblocks, idx, PETSC_COPY_VALUES, &points));
  PetscCall(MatPermute(A, points, points, &lu->P));
  PetscCall(ISDestroy(&points));
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, blocked, &nrow, &ia, &ja, &done));
  PetscCall(MatGetRowIJ(lu->P, 0, PETSC_FALSE, blocked, &prow, &ip, &jp, &pdone));
  PetscCheck(done && pdone && nrow == lu->nblocks && prow == lu->nblocks, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "newton: the subdomain's ordering has %" PetscInt_FMT " blocks for %" PetscInt_FMT " and %" PetscInt_FMT " block rows",
             lu->nblocks, nrow, prow);
  lu->nstored = ip[prow];
  PetscCall(PetscMalloc2(lu->nblocks, &lu->perm, lu->nstored, &lu->src_block));
  PetscCall(PetscMalloc1(lu->nblocks, &pos_in_row));
  for (PetscInt i = 0; i < lu->nblocks; i++) {
    const PetscInt a = idx[i];
    lu->perm[i]      = a;
    for (PetscInt k = ia[a]; k < ia[a + 1]; k++) pos_in_row[ja[k]] = k;
    for (PetscInt k = ip[i]; k < ip[i + 1]; k++) lu->src_block[k] = pos_in_row[idx[jp[k]]];
  }
  PetscCall(PetscFree(pos_in_row));
  PetscCall(MatRestoreRowIJ(lu->P, 0, PETSC_FALSE, blocked, &prow, &ip, &jp, &pdone));
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, blocked, &nrow, &ia, &ja, &done));
  PetscCall(ISRestoreIndices(rows, &idx));
  PetscCall(ISDestroy(&rows));
  PetscCall(ISDestroy(&cols));
  PetscCall(MatCreateVecs(lu->P, &lu->xs, &lu->ys));
  PetscCall(KSPSetOperators(lu->factor, lu->P, lu->P));
  PetscFunctionReturn(0);
}

/* A's values into P, block by block (an inline copy: a library call per 2 x 2 block is what the permuted kernel pays). */
static PetscErrorCode SortedLUCopyValues(SortedLU *lu, Mat A)
{
  PetscScalar   *a, *p;
  const PetscInt bs2 = lu->bs * lu->bs;
  PetscBool      blocked;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATSEQBAIJ, &blocked));
  if (blocked) {
    PetscCall(MatSeqBAIJGetArray(A, &a)); /* only read (PETSc 3.18 has no read-only access to a BAIJ array) */
    PetscCall(MatSeqBAIJGetArray(lu->P, &p));
  } else {
    PetscCall(MatSeqAIJGetArrayRead(A, (const PetscScalar **)&a));
    PetscCall(MatSeqAIJGetArray(lu->P, &p));
  }
  for (PetscInt k = 0; k < lu->nstored; k++) {
    const PetscScalar *from = a + lu->src_block[k] * bs2;
    PetscScalar       *to   = p + k * bs2;
    for (PetscInt e = 0; e < bs2; e++) to[e] = from[e];
  }
  if (blocked) {
    PetscCall(MatSeqBAIJRestoreArray(lu->P, &p));
    PetscCall(MatSeqBAIJRestoreArray(A, &a));
  } else {
    PetscCall(MatSeqAIJRestoreArray(lu->P, &p));
    PetscCall(MatSeqAIJRestoreArrayRead(A, (const PetscScalar **)&a));
  }
  PetscCall(MatAssemblyBegin(lu->P, MAT_FINAL_ASSEMBLY)); /* values changed through the array: P changed */
  PetscCall(MatAssemblyEnd(lu->P, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* Once per factorization: P built when the subdomain matrix is new or its pattern changed (a new step), else its values
   copied; then P factored. A failed factorization is the subdomain's failure, seen by PCASM. */
static PetscErrorCode SortedLUSetUp(PC pc)
{
  SortedLU        *lu;
  Mat              A;
  PC               inner;
  PCFailedReason   reason;
  PetscInt64       id;
  PetscObjectState pattern;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &lu));
  PetscCall(PCGetOperators(pc, NULL, &A));
  PetscCall(PetscObjectGetId((PetscObject)A, &id));
  PetscCall(MatGetNonzeroState(A, &pattern));
  if (!lu->P || id != lu->id || pattern != lu->pattern) {
    PetscCall(SortedLUClear(lu));
    PetscCall(SortedLUBuild(lu, A));
    lu->id      = id;
    lu->pattern = pattern;
  } else
    PetscCall(SortedLUCopyValues(lu, A));
  PetscCall(KSPSetUp(lu->factor));
  PetscCall(KSPGetPC(lu->factor, &inner));
  PetscCall(PCSetUp(inner)); /* KSPSetUp does not set a set-up PC up again; PCSetUp factors P when it changed */
  PetscCall(PCGetFailedReason(inner, &reason));
  PetscCall(PCSetFailedReason(pc, reason));
  PetscFunctionReturn(0);
}

/* y = A^-1 x: x into P's order, the triangular solves (the factor's PCApply), y back. */
static PetscErrorCode SortedLUApply(PC pc, Vec x, Vec y)
{
  SortedLU          *lu;
  PC                 inner;
  const PetscScalar *xa, *ya;
  PetscScalar       *xs, *yo;
  PetscInt           bs;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &lu));
  bs = lu->bs;
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArray(lu->xs, &xs));
  for (PetscInt i = 0; i < lu->nblocks; i++)
    for (PetscInt c = 0; c < bs; c++) xs[i * bs + c] = xa[lu->perm[i] * bs + c];
  PetscCall(VecRestoreArray(lu->xs, &xs));
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(KSPGetPC(lu->factor, &inner));
  PetscCall(PCApply(inner, lu->xs, lu->ys));
  PetscCall(VecGetArrayRead(lu->ys, &ya));
  PetscCall(VecGetArray(y, &yo));
  for (PetscInt i = 0; i < lu->nblocks; i++)
    for (PetscInt c = 0; c < bs; c++) yo[lu->perm[i] * bs + c] = ya[i * bs + c];
  PetscCall(VecRestoreArray(y, &yo));
  PetscCall(VecRestoreArrayRead(lu->ys, &ya));
  PetscFunctionReturn(0);
}

static PetscErrorCode SortedLUDestroy(PC pc)
{
  SortedLU *lu;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &lu));
  PetscCall(SortedLUClear(lu));
  PetscCall(KSPDestroy(&lu->factor));
  PetscCall(PetscFree(lu));
  PetscFunctionReturn(0);
}

/* Whether pc is this LU (a PCSHELL of this name). */
static PetscErrorCode IsSortedLU(PC pc, PetscBool *is)
{
  const char *name;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCSHELL, is));
  if (!*is) PetscFunctionReturn(0);
  PetscCall(PCShellGetName(pc, &name));
  PetscCall(PetscStrcmp(name, SORTED_LU_NAME, is));
  PetscFunctionReturn(0);
}

/* Makes subpc (a subdomain solver of PCASM, on a sequential BAIJ matrix, or AIJ of block size 1) this LU, unless it
   already is. */
PetscErrorCode NewtonSubdomainSetSortedLU(PC subpc)
{
  SortedLU *lu;
  PC        inner;
  PetscBool is;

  PetscFunctionBeginUser;
  PetscCall(IsSortedLU(subpc, &is));
  if (is) PetscFunctionReturn(0);
  PetscCall(PetscNew(&lu));
  PetscCall(KSPCreate(PETSC_COMM_SELF, &lu->factor));
  PetscCall(KSPSetType(lu->factor, KSPPREONLY));
  PetscCall(KSPGetPC(lu->factor, &inner));
  PetscCall(PCSetType(inner, PCLU));
  PetscCall(PCFactorSetMatSolverType(inner, MATSOLVERPETSC));
  PetscCall(PCFactorSetMatOrderingType(inner, MATORDERINGNATURAL));
  PetscCall(KSPSetErrorIfNotConverged(lu->factor, PETSC_FALSE));
  PetscCall(PCSetType(subpc, PCSHELL));
  PetscCall(PCShellSetContext(subpc, lu));
  PetscCall(PCShellSetSetUp(subpc, SortedLUSetUp));
  PetscCall(PCShellSetApply(subpc, SortedLUApply));
  PetscCall(PCShellSetDestroy(subpc, SortedLUDestroy));
  PetscCall(PCShellSetName(subpc, SORTED_LU_NAME));
  PetscFunctionReturn(0);
}

/* Frees what subpc holds for the step that ends (P, its factor): PETSc 3.18's PCSHELL has no reset, and the factor is
   the largest object on a rank. Nothing when subpc is not this LU. */
PetscErrorCode NewtonSubdomainReleaseSortedLU(PC subpc)
{
  SortedLU *lu;
  PetscBool is;

  PetscFunctionBeginUser;
  PetscCall(IsSortedLU(subpc, &is));
  if (!is) PetscFunctionReturn(0);
  PetscCall(PCShellGetContext(subpc, &lu));
  PetscCall(SortedLUClear(lu));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* The subdomain matrices of kergs's additive Schwarz, computed from W's                            */

/* J = A + B (W + sigma I) + eps I block row by block row, so a subdomain's J is its W with each block row scaled by
   that row's B and A + sigma B + eps I added to its own block. W does not change within a step: each rank extracts its
   subdomain of W once per J (per step, and per working set), and at every later set-up only the A and B blocks of
   the subdomain's rows travel (the overlap's come from the other ranks), instead of PCASM extracting the subdomain of J
   again (MatCreateSubMatrices: 1.55 s of 14.4 s on the 100,000-disk strip, 2 ranks, 72 set-ups). The preconditioning
   matrix handed to PCASM is a shell that does this; J itself stays the operator. */
typedef struct {
  Newton    *nt;
  Mat        W;      /* J's template: W over J's rows, in J's order */
  IS         rows;   /* the subdomain's rows, as PCASM gave them at the first extraction */
  Mat       *Wsub;   /* W over the subdomain (one, as PCASM extracts it) */
  Vec        blocks; /* the subdomain rows' A and B blocks */
  VecScatter gather; /* nt->row_AB -> blocks */
  PetscInt  *diag;   /* per subdomain block row: position of its own block */
  PetscInt   nrows;  /* subdomain block rows */
} SubdomainSource;

static PetscErrorCode SourceClear(SubdomainSource *src)
{
  PetscFunctionBeginUser;
  if (src->Wsub) PetscCall(MatDestroySubMatrices(1, &src->Wsub));
  PetscCall(ISDestroy(&src->rows));
  PetscCall(VecDestroy(&src->blocks));
  PetscCall(VecScatterDestroy(&src->gather));
  PetscCall(PetscFree(src->diag));
  PetscFunctionReturn(0);
}

static PetscErrorCode SourceDestroy(Mat P)
{
  SubdomainSource *src;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(P, &src));
  PetscCall(SourceClear(src));
  PetscCall(MatDestroy(&src->W));
  PetscCall(PetscFree(src));
  PetscFunctionReturn(0);
}

/* The overlap grows on J's own graph (W's pattern). */
static PetscErrorCode SourceIncreaseOverlap(Mat P, PetscInt n, IS is[], PetscInt ov)
{
  SubdomainSource *src;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(P, &src));
  PetscCall(MatIncreaseOverlap(src->nt->J, n, is, ov));
  PetscFunctionReturn(0);
}

/* At J's first set-up: the subdomain of J and of W extracted (same pattern), the scatter of the rows' blocks and the
   position of each row's own block. */
static PetscErrorCode SourceBuild(SubdomainSource *src, Mat sub, IS rows)
{
  const PetscInt *points;
  PetscInt        npoints, nc, *block_rows;
  IS              from;

  PetscFunctionBeginUser;
  PetscCall(SourceClear(src));
  PetscCall(MatCreateSubMatrices(src->W, 1, &rows, &rows, MAT_INITIAL_MATRIX, &src->Wsub));
  PetscCall(PetscObjectReference((PetscObject)rows));
  src->rows = rows;
  PetscCall(MatGetBlockSize(src->W, &nc));
  PetscCall(ISGetLocalSize(rows, &npoints));
  src->nrows = npoints / nc;
  PetscCall(PetscMalloc1(src->nrows, &block_rows));
  PetscCall(ISGetIndices(rows, &points));
  for (PetscInt i = 0; i < src->nrows; i++) block_rows[i] = points[i * nc] / nc;
  PetscCall(ISRestoreIndices(rows, &points));
  PetscCall(ISCreateBlock(PETSC_COMM_SELF, 2 * nc * nc, src->nrows, block_rows, PETSC_OWN_POINTER, &from));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, src->nrows * 2 * nc * nc, &src->blocks));
  PetscCall(VecScatterCreate(src->nt->row_AB, from, src->blocks, NULL, &src->gather));
  PetscCall(ISDestroy(&from));
  PetscCall(PetscMalloc1(src->nrows, &src->diag));
  PetscCall(NewtonLocateOwnBlocks(sub, nc, src->diag));
  PetscFunctionReturn(0);
}

/* sub = A + B (Wsub + sigma I) + eps I over the subdomain's rows, with the blocks of the J last assembled. */
static PetscErrorCode SourceFill(SubdomainSource *src, Mat sub)
{
  const Newton      *nt = src->nt;
  const PetscScalar *ab; /* real scalars: kergs is built on real PETSc */
  PetscInt           nc;

  PetscFunctionBeginUser;
  PetscCall(VecScatterBegin(src->gather, nt->row_AB, src->blocks, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(src->gather, nt->row_AB, src->blocks, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(MatGetBlockSize(src->W, &nc));
  PetscCall(VecGetArrayRead(src->blocks, &ab));
  PetscCall(
      NewtonScaleRows(src->Wsub[0], sub, src->nrows, nc, ab, ab + nc * nc, 2 * nc * nc, NULL, src->diag, nt->sigma_used, nt->eps_used));
  PetscCall(VecRestoreArrayRead(src->blocks, &ab));
  PetscCall(MatAssemblyBegin(sub, MAT_FINAL_ASSEMBLY)); /* values changed through the array */
  PetscCall(MatAssemblyEnd(sub, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* PCASM's extraction: the first from J itself (and W's subdomain kept), the later ones computed (SourceFill). The shell
   exists only with one subdomain per rank (NewtonSubdomainsFromW); anything else, on any rank, is extracted from J
   (decided by all ranks together: the scatter is collective). */
static PetscErrorCode SourceCreateSubMatrices(Mat P, PetscInt n, const IS irow[], const IS icol[], MatReuse scall, Mat *sub[])
{
  SubdomainSource *src;
  PetscBool        same;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(P, &src));
  same = (PetscBool)(n == 1);
  if (same && irow[0] != icol[0]) PetscCall(ISEqual(irow[0], icol[0], &same));
  if (same && src->rows && scall == MAT_REUSE_MATRIX && irow[0] != src->rows) PetscCall(ISEqual(irow[0], src->rows, &same));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &same, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)P)));
  if (!same) {
    PetscCall(MatCreateSubMatrices(src->nt->J, n, irow, icol, scall, sub));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscLogEventBegin(KERGS_Subdomain, P, 0, 0, 0));
  if (scall == MAT_INITIAL_MATRIX || !src->Wsub) {
    if (scall == MAT_REUSE_MATRIX) PetscCall(MatDestroySubMatrices(n, sub));
    PetscCall(MatCreateSubMatrices(src->nt->J, 1, irow, icol, MAT_INITIAL_MATRIX, sub));
    PetscCall(SourceBuild(src, (*sub)[0], irow[0]));
  } else
    PetscCall(SourceFill(src, (*sub)[0]));
  src->nt->subdomains_computed++;
  PetscCall(PetscLogEventEnd(KERGS_Subdomain, P, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Whether kergs's additive Schwarz takes its subdomain matrices from W's: -solver_newton_subdomains_from_w, several
   ranks, kergs's choice of linear solver, and one subdomain per rank, each used as PCASM extracts it (not with
   -solver_pc_asm_blocks, -solver_pc_asm_local_blocks, which make PCASM partition each rank's rows through the
   matrix's diagonal block, nor -solver_pc_asm_sub_mat_type, which converts every extraction anew). */
PetscErrorCode NewtonSubdomainsFromW(Newton *nt, PetscBool *apply)
{
  PetscMPIInt size;
  const char *prefix;
  const char *names[] = {"pc_asm_blocks", "pc_asm_local_blocks", "pc_asm_sub_mat_type"};
  char        name[256];
  PetscBool   given;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)nt->ksp), &size));
  *apply = (PetscBool)(nt->subdomains_from_w && size > 1 && !nt->user_pc);
  PetscCall(KSPGetOptionsPrefix(nt->ksp, &prefix));
  for (size_t k = 0; k < sizeof(names) / sizeof(names[0]) && *apply; k++) {
    PetscCall(PetscSNPrintf(name, sizeof(name), "-%s%s", prefix ? prefix : "", names[k]));
    PetscCall(PetscOptionsHasName(NULL, NULL, name, &given));
    if (given) *apply = PETSC_FALSE;
  }
  PetscFunctionReturn(0);
}

/* The preconditioning matrix of kergs's additive Schwarz for nt->J (J's template W over J's rows, in J's order), and
   nt->row_AB, which NewtonSubdomainSetBlocks fills at every assembly of J. */
PetscErrorCode NewtonSubdomainCreateSource(Newton *nt, Mat W, Mat *P)
{
  SubdomainSource *src;
  PetscInt         m, N, nc;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&src));
  src->nt = nt;
  src->W  = W;
  PetscCall(PetscObjectReference((PetscObject)W));
  PetscCall(MatGetLocalSize(nt->J, &m, NULL));
  PetscCall(MatGetSize(nt->J, &N, NULL));
  PetscCall(MatGetBlockSize(nt->J, &nc));
  PetscCall(MatCreateShell(PetscObjectComm((PetscObject)nt->J), m, m, N, N, src, P));
  PetscCall(MatSetBlockSize(*P, nc));
  PetscCall(MatShellSetOperation(*P, MATOP_CREATE_SUBMATRICES, (void (*)(void))SourceCreateSubMatrices));
  PetscCall(MatShellSetOperation(*P, MATOP_INCREASE_OVERLAP, (void (*)(void))SourceIncreaseOverlap));
  PetscCall(MatShellSetOperation(*P, MATOP_DESTROY, (void (*)(void))SourceDestroy));
  PetscCall(MatSetUp(*P));
  PetscCall(VecDestroy(&nt->row_AB));
  PetscCall(VecCreateMPI(PetscObjectComm((PetscObject)nt->J), (m / nc) * 2 * nc * nc, PETSC_DETERMINE, &nt->row_AB));
  PetscCall(VecSetBlockSize(nt->row_AB, 2 * nc * nc));
  PetscFunctionReturn(0);
}

/* The blocks of the J just assembled (Aused, Bused over J's rows), and the shell told that J changed. */
PetscErrorCode NewtonSubdomainSetBlocks(Newton *nt, PetscInt nc)
{
  PetscScalar *ab;

  PetscFunctionBeginUser;
  if (!nt->Pschwarz) PetscFunctionReturn(0);
  PetscCall(VecGetArray(nt->row_AB, &ab));
  for (PetscInt a = 0; a < nt->nrows; a++) {
    const PetscInt contact = NewtonRowContact(nt, a);
    for (PetscInt k = 0; k < nc * nc; k++) {
      ab[a * 2 * nc * nc + k]           = nt->Aused[contact * nc * nc + k];
      ab[a * 2 * nc * nc + nc * nc + k] = nt->Bused[contact * nc * nc + k];
    }
  }
  PetscCall(VecRestoreArray(nt->row_AB, &ab));
  PetscCall(MatAssemblyBegin(nt->Pschwarz, MAT_FINAL_ASSEMBLY)); /* a new state: PCSetUp sets the preconditioner up again */
  PetscCall(MatAssemblyEnd(nt->Pschwarz, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}
