/* The subdomain solver of solver type "newton"'s additive Schwarz (several ranks, newton_linear.c): the subdomain's
   matrix, as PCASM extracts it (its rows in increasing order), copied block by block into the subdomain's own AMD order
   and factored there by PETSc's LU with the natural ordering, as one rank's J is (PresortContacts). PETSc's kernel for
   a permuted 2 x 2-block matrix copies and zeroes every block through a library call, its natural-ordering kernel
   does not. Handing PCASM the subdomain already in AMD order instead (PCASMSetLocalSubdomains, sorting off) made its
   extraction take the unsorted path of MatCreateSubMatrices: on the 100,000-disk strip, 2 ranks, the factorizations
   and triangular solves took 16 % and 22 % less time and the extractions 125 % more, no gain at all. The order, the
   permuted pattern and the map between the two value arrays are built once per step (the pattern is the step's);
   each factorization then costs one pass over the blocks more. */
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
