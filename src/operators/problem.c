/* kergs operators: a contact problem given as data (W, q = v^d) instead of assembled from a scene, as read from an
   FCLib file (src/step/fclib_run.c). Only the contact-side objects exist then: W, v^d, r and v; no H, no DOF vectors
   (the solvers that read H_f, the kernel-regularised ones, cannot run on such a problem). */
#include <kergs/private/operatorsimpl.h>

/* Block pattern of this rank's block rows of the upper block triangle of W (blocks bj >= bi): per local block row, the
   blocks in the diagonal part (columns owned here) and in the off-diagonal part. */
static PetscErrorCode ProblemCountBlocks(PetscInt bs, PetscInt bstart, PetscInt bend, const PetscInt rowptr[], const PetscInt colind[],
                                         PetscInt nblocks, PetscInt *dnnz, PetscInt *onnz)
{
  PetscInt *mark;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nblocks, &mark));
  for (PetscInt bj = 0; bj < nblocks; bj++) mark[bj] = -1;
  for (PetscInt bi = bstart; bi < bend; bi++) {
    dnnz[bi - bstart] = onnz[bi - bstart] = 0;
    for (PetscInt i = bi * bs; i < (bi + 1) * bs; i++)
      for (PetscInt e = rowptr[i]; e < rowptr[i + 1]; e++) {
        const PetscInt bj = colind[e] / bs;
        if (bj < bi || mark[bj] == bi) continue;
        mark[bj] = bi;
        if (bj < bend)
          dnnz[bi - bstart]++;
        else
          onnz[bi - bstart]++;
      }
    if (mark[bi] != bi) dnnz[bi - bstart]++; /* the diagonal block is always stored (the sweep reads it in place) */
  }
  PetscCall(PetscFree(mark));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsSetProblem(KergsOperators ops, PetscInt nlocal, PetscInt ncomp, const PetscInt rowptr[],
                                        const PetscInt colind[], const PetscReal val[], const PetscReal q[])
{
  PetscInt     bstart = 0, bend, nblocks, *dnnz, *onnz, nnz = 0;
  PetscScalar *vd;

  PetscFunctionBeginUser;
  PetscCheck(ncomp == 1 || ncomp == KERGS_DIM, ops->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "A contact problem has 1 or %d components per contact, not %" PetscInt_FMT, KERGS_DIM, ncomp);
  PetscCall(KergsOperatorsReleaseH(ops));
  PetscCall(KergsOperatorsReleaseW(ops));
  PetscCall(VecDestroy(&ops->vd));
  PetscCall(VecDestroy(&ops->r));
  PetscCall(VecDestroy(&ops->v));
  PetscCallMPI(MPI_Exscan(&nlocal, &bstart, 1, MPIU_INT, MPI_SUM, ops->comm));
  PetscCall(MPIU_Allreduce(&nlocal, &nblocks, 1, MPIU_INT, MPI_SUM, ops->comm));
  {
    PetscMPIInt rank;
    PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
    if (rank == 0) bstart = 0; /* MPI_Exscan leaves rank 0's result undefined */
  }
  bend = bstart + nlocal;
  PetscCall(PetscMalloc2(nlocal, &dnnz, nlocal, &onnz));
  PetscCall(ProblemCountBlocks(ncomp, bstart, bend, rowptr, colind, nblocks, dnnz, onnz));
  PetscCall(MatCreate(ops->comm, &ops->W));
  PetscCall(MatSetSizes(ops->W, nlocal * ncomp, nlocal * ncomp, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetType(ops->W, MATSBAIJ));
  PetscCall(MatSeqSBAIJSetPreallocation(ops->W, ncomp, 0, dnnz));
  PetscCall(MatMPISBAIJSetPreallocation(ops->W, ncomp, 0, dnnz, 0, onnz));
  PetscCall(MatSetOption(ops->W, MAT_IGNORE_LOWER_TRIANGULAR, PETSC_TRUE));
  PetscCall(PetscFree2(dnnz, onnz));
  for (PetscInt i = bstart * ncomp; i < bend * ncomp; i++) {
    PetscScalar zero = 0.0;
    PetscBool   diag = PETSC_FALSE;
    for (PetscInt e = rowptr[i]; e < rowptr[i + 1]; e++) {
      PetscScalar x = val[e];
      if (colind[e] / ncomp < i / ncomp) continue; /* the upper block triangle only: W is symmetric */
      PetscCall(MatSetValues(ops->W, 1, &i, 1, &colind[e], &x, INSERT_VALUES));
      diag = (PetscBool)(diag || colind[e] == i);
    }
    if (!diag) PetscCall(MatSetValues(ops->W, 1, &i, 1, &i, &zero, INSERT_VALUES)); /* the diagonal exists even when zero */
  }
  PetscCall(MatAssemblyBegin(ops->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ops->W, MAT_FINAL_ASSEMBLY));
  for (PetscInt i = 0; i < nblocks * ncomp; i++) nnz += rowptr[i + 1] - rowptr[i];
  ops->nnz_W         = (PetscReal)nnz;
  ops->nnz_Hf        = 0.0;
  ops->W_active_only = PETSC_TRUE; /* every contact of a given problem is active */
  ops->ncomp         = ncomp;
  ops->ndof_disk     = 0;
  ops->nfreewalls = ops->ndrivenwalls = 0;
  ops->nfree = ops->nfree_local = ops->ngiven = 0;
  PetscCall(MatCreateVecs(ops->W, &ops->vd, &ops->r));
  PetscCall(VecDuplicate(ops->r, &ops->v));
  PetscCall(VecGetArray(ops->vd, &vd));
  for (PetscInt i = 0; i < nlocal * ncomp; i++) vd[i] = q[bstart * ncomp + i];
  PetscCall(VecRestoreArray(ops->vd, &vd));
  PetscCall(VecZeroEntries(ops->r));
  PetscCall(VecCopy(ops->vd, ops->v));
  PetscFunctionReturn(0);
}
