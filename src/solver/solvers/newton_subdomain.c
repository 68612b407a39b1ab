/* The subdomain solver of solver type "newton"'s additive Schwarz (several ranks, newton_linear.c): the subdomain's
   matrix, as PCASM extracts it (its rows in increasing order), copied block by block into the subdomain's own AMD order
   and factored there by PETSc's LU with the natural ordering, as one rank's J is (PresortContacts). PETSc's kernel for
   a permuted 2 x 2-block matrix copies and zeroes every block through a library call, its natural-ordering kernel
   does not. Handing PCASM the subdomain already in AMD order instead (PCASMSetLocalSubdomains, sorting off) made its
   extraction take the unsorted path of MatCreateSubMatrices: on the 100,000-disk strip, 2 ranks, the factorizations
   and triangular solves took 16 % and 22 % less time and the extractions 125 % more, no gain in all. The order, the
   permuted pattern and the map between the two value arrays are built once per step (the pattern is the step's);
   each factorization then costs one pass over the blocks more. */
#include "newton.h"
#include <string.h>

typedef struct {
  KSP              lu;   /* LU, natural ordering, of P */
  Mat              P;    /* the subdomain's matrix in its AMD order: P(i, j) = A(perm[i], perm[j]), by blocks */
  PetscInt        *perm; /* P's block row i is the subdomain's block row perm[i] */
  PetscInt        *map;  /* P's k-th stored block is the subdomain matrix's map[k]-th */
  PetscInt         nb, nnzb, bs;
  PetscInt64       id; /* the subdomain matrix P was built for, and its pattern */
  PetscObjectState pattern;
  Vec              xs, ys; /* right-hand side and solution in P's order */
} SortedLU;

static PetscErrorCode SortedLUClear(SortedLU *lu)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&lu->P));
  PetscCall(VecDestroy(&lu->xs));
  PetscCall(VecDestroy(&lu->ys));
  PetscCall(PetscFree2(lu->perm, lu->map));
  if (lu->lu) PetscCall(KSPReset(lu->lu));
  PetscFunctionReturn(0);
}

/* perm from AMD on A's block pattern, P = A permuted, and map: for each block row i of P (A's row perm[i]), the
   position in A's value array of each of its blocks, found through A's row marked by column. */
static PetscErrorCode SortedLUBuild(SortedLU *lu, Mat A)
{
  IS              rows, cols, points;
  const PetscInt *idx, *ia, *ja, *ip, *jp;
  PetscInt        nrow, prow, *where;
  PetscBool       done;

  PetscFunctionBeginUser;
  PetscCall(MatGetBlockSize(A, &lu->bs));
  PetscCall(MatGetOrdering(A, MATORDERINGAMD, &rows, &cols));
  PetscCall(ISGetLocalSize(rows, &lu->nb));
  PetscCall(ISGetIndices(rows, &idx));
  PetscCall(ISCreateBlock(PETSC_COMM_SELF, lu->bs, lu->nb, idx, PETSC_COPY_VALUES, &points));
  PetscCall(MatPermute(A, points, points, &lu->P));
  PetscCall(ISDestroy(&points));
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_TRUE, &nrow, &ia, &ja, &done));
  PetscCheck(done && nrow == lu->nb, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "newton: the subdomain's ordering has %" PetscInt_FMT " blocks for %" PetscInt_FMT " block rows", lu->nb, nrow);
  PetscCall(MatGetRowIJ(lu->P, 0, PETSC_FALSE, PETSC_TRUE, &prow, &ip, &jp, &done));
  lu->nnzb = ip[prow];
  PetscCall(PetscMalloc2(lu->nb, &lu->perm, lu->nnzb, &lu->map));
  PetscCall(PetscMalloc1(lu->nb, &where));
  for (PetscInt i = 0; i < lu->nb; i++) {
    const PetscInt a = idx[i];
    lu->perm[i]      = a;
    for (PetscInt k = ia[a]; k < ia[a + 1]; k++) where[ja[k]] = k;
    for (PetscInt k = ip[i]; k < ip[i + 1]; k++) lu->map[k] = where[idx[jp[k]]];
  }
  PetscCall(PetscFree(where));
  PetscCall(MatRestoreRowIJ(lu->P, 0, PETSC_FALSE, PETSC_TRUE, &prow, &ip, &jp, &done));
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_TRUE, &nrow, &ia, &ja, &done));
  PetscCall(ISRestoreIndices(rows, &idx));
  PetscCall(ISDestroy(&rows));
  PetscCall(ISDestroy(&cols));
  PetscCall(MatCreateVecs(lu->P, &lu->xs, &lu->ys));
  PetscCall(KSPSetOperators(lu->lu, lu->P, lu->P));
  PetscFunctionReturn(0);
}

/* A's values into P, block by block. */
static PetscErrorCode SortedLUCopyValues(SortedLU *lu, Mat A)
{
  PetscScalar   *a, *p;
  const PetscInt bs2 = lu->bs * lu->bs;
  PetscBool      blocked;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATSEQBAIJ, &blocked)); /* else AIJ: frictionless, one component */
  if (blocked) {
    PetscCall(MatSeqBAIJGetArray(A, &a)); /* only read (PETSc 3.18 has no read-only access to a BAIJ array) */
    PetscCall(MatSeqBAIJGetArray(lu->P, &p));
  } else {
    PetscCall(MatSeqAIJGetArrayRead(A, (const PetscScalar **)&a));
    PetscCall(MatSeqAIJGetArray(lu->P, &p));
  }
  for (PetscInt k = 0; k < lu->nnzb; k++) PetscCall(PetscArraycpy(p + k * bs2, a + lu->map[k] * bs2, bs2));
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
  PetscCall(KSPSetUp(lu->lu));
  PetscCall(KSPGetPC(lu->lu, &inner));
  PetscCall(PCSetUp(inner)); /* KSPSetUp does not set a set-up PC up again; PCSetUp factors P when it changed */
  PetscCall(PCGetFailedReason(inner, &reason));
  PetscCall(PCSetFailedReason(pc, reason));
  PetscFunctionReturn(0);
}

/* y = A^-1 x: x into P's order, the triangular solves, y back. */
static PetscErrorCode SortedLUApply(PC pc, Vec x, Vec y)
{
  SortedLU          *lu;
  const PetscScalar *xa, *ya;
  PetscScalar       *xs, *yo;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &lu));
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArray(lu->xs, &xs));
  for (PetscInt i = 0; i < lu->nb; i++)
    for (PetscInt c = 0; c < lu->bs; c++) xs[i * lu->bs + c] = xa[lu->perm[i] * lu->bs + c];
  PetscCall(VecRestoreArray(lu->xs, &xs));
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(KSPSolve(lu->lu, lu->xs, lu->ys));
  PetscCall(VecGetArrayRead(lu->ys, &ya));
  PetscCall(VecGetArray(y, &yo));
  for (PetscInt i = 0; i < lu->nb; i++)
    for (PetscInt c = 0; c < lu->bs; c++) yo[lu->perm[i] * lu->bs + c] = ya[i * lu->bs + c];
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
  PetscCall(KSPDestroy(&lu->lu));
  PetscCall(PetscFree(lu));
  PetscFunctionReturn(0);
}

/* Makes subpc (a subdomain solver of PCASM, on a sequential BAIJ matrix) this LU, unless it already is. */
PetscErrorCode NewtonSubdomainSetSortedLU(PC subpc)
{
  SortedLU *lu;
  PC        inner;
  PetscBool shell;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompare((PetscObject)subpc, PCSHELL, &shell));
  if (shell) PetscFunctionReturn(0);
  PetscCall(PetscNew(&lu));
  PetscCall(KSPCreate(PETSC_COMM_SELF, &lu->lu));
  PetscCall(KSPSetType(lu->lu, KSPPREONLY));
  PetscCall(KSPGetPC(lu->lu, &inner));
  PetscCall(PCSetType(inner, PCLU));
  PetscCall(PCFactorSetMatSolverType(inner, MATSOLVERPETSC));
  PetscCall(PCFactorSetMatOrderingType(inner, MATORDERINGNATURAL));
  PetscCall(KSPSetErrorIfNotConverged(lu->lu, PETSC_FALSE));
  PetscCall(PCSetType(subpc, PCSHELL));
  PetscCall(PCShellSetContext(subpc, lu));
  PetscCall(PCShellSetSetUp(subpc, SortedLUSetUp));
  PetscCall(PCShellSetApply(subpc, SortedLUApply));
  PetscCall(PCShellSetDestroy(subpc, SortedLUDestroy));
  PetscCall(PCShellSetName(subpc, "LU with AMD, the subdomain copied into that order (natural-ordering kernel)"));
  PetscFunctionReturn(0);
}
