/* kergs predictor type "unilateral": the frictionless unilateral problem solved exactly on the normal
   components of the active contacts (the paper's "prédicteur unilatéral", section 3), no parameter:
     v_n = W_nn r_n + v^d_n,   0 <= v_n _|_ r_n >= 0 (active),   r_n = 0 (inactive),
   by NLGS sweeps (include/kergs/nlgs.h, one component per contact, mu = 0) on the normal sub-block W_nn of W,
   warm-started from the contacts' impulses, until the W-weighted change quad < -predictor_unilateral_tol or
   -predictor_unilateral_max_it sweeps. Without friction in the scene W_nn is W itself. */
#include <kergs/predictor.h>
#include <kergs/nlgs.h>

typedef struct {
  PetscReal  tol;
  PetscInt   max_it;
  KergsSweep sweep;
  PetscReal  quad; /* last sweep's quad */
} Predictor_Unilateral;

static PetscErrorCode KergsPredictorSetFromOptions_Unilateral(KergsPredictor p, PetscOptionItems *PetscOptionsObject)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "Unilateral predictor (exact frictionless problem, NLGS)");
  PetscCall(PetscOptionsReal("-predictor_unilateral_tol",
                             "Stop the NLGS sweeps when the W-weighted relative change of r_n (quad) is below this", "", u->tol, &u->tol,
                             NULL));
  PetscCall(PetscOptionsInt("-predictor_unilateral_max_it", "Maximum number of NLGS sweeps of the unilateral predictor", "", u->max_it,
                            &u->max_it, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(u->tol > 0 && PetscIsNormalReal(u->tol), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-predictor_unilateral_tol %g must be a positive finite number", (double)u->tol);
  PetscCheck(u->max_it >= 1, p->comm, PETSC_ERR_ARG_OUTOFRANGE, "-predictor_unilateral_max_it %" PetscInt_FMT " must be at least 1",
             u->max_it);
  PetscFunctionReturn(0);
}

/* Number of blocks in each block row of a local block A of a BAIJ W. */
static PetscErrorCode BlockRowCounts(Mat A, PetscInt *nz)
{
  const PetscInt *ia, *ja;
  PetscInt        nrow;
  PetscBool       done;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_TRUE, &nrow, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "unilateral predictor: no block CSR arrays for W");
  for (PetscInt a = 0; a < nrow; a++) nz[a] = ia[a + 1] - ia[a];
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_TRUE, &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* W_nn(alpha, beta) = (W_alpha,beta)_nn, the first entry of each block of a local block A of W: block column j
   is the global contact garray[j] (off-process block) or cstart + j. */
static PetscErrorCode SetNormalEntries(Mat Wnn, Mat A, PetscInt nc, PetscInt rstart, PetscInt cstart, const PetscInt *garray)
{
  const PetscInt *ia, *ja;
  PetscInt        nrow, row, col;
  PetscBool       done;
  PetscScalar    *v;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_TRUE, &nrow, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "unilateral predictor: no block CSR arrays for W");
  PetscCall(MatSeqBAIJGetArray(A, &v));
  for (PetscInt a = 0; a < nrow; a++)
    for (PetscInt j = ia[a]; j < ia[a + 1]; j++) {
      row = rstart + a;
      col = garray ? garray[ja[j]] : cstart + ja[j];
      PetscCall(MatSetValues(Wnn, 1, &row, 1, &col, &v[j * nc * nc], INSERT_VALUES));
    }
  PetscCall(MatSeqBAIJRestoreArray(A, &v));
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_TRUE, &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* W_nn from a (seq|mpi)baij W with block size nc, read from its blocks (PETSc's BAIJ extracts whole blocks
   only, and converting an MPIBAIJ W to AIJ re-assembles W itself); contact alpha is row and column alpha. */
static PetscErrorCode NormalFromBlocks(Mat W, PetscInt nc, Mat *Wnn)
{
  Mat             Ad, Ao = NULL;
  const PetscInt *garray = NULL;
  PetscInt        m, n, rstart, *dnz, *onz;
  PetscBool       mpi;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompare((PetscObject)W, MATMPIBAIJ, &mpi));
  if (mpi) PetscCall(MatMPIBAIJGetSeqBAIJ(W, &Ad, &Ao, &garray));
  else Ad = W;
  PetscCall(MatGetLocalSize(W, &m, NULL));
  PetscCall(MatGetOwnershipRange(W, &rstart, NULL));
  n = m / nc;
  rstart /= nc;
  PetscCall(PetscCalloc2(n, &dnz, n, &onz));
  PetscCall(BlockRowCounts(Ad, dnz));
  if (Ao) PetscCall(BlockRowCounts(Ao, onz));
  PetscCall(MatCreateAIJ(PetscObjectComm((PetscObject)W), n, n, PETSC_DETERMINE, PETSC_DETERMINE, 0, dnz, 0, onz, Wnn));
  PetscCall(MatSetOption(*Wnn, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(SetNormalEntries(*Wnn, Ad, nc, rstart, rstart, NULL));
  if (Ao) PetscCall(SetNormalEntries(*Wnn, Ao, nc, rstart, 0, garray));
  PetscCall(MatAssemblyBegin(*Wnn, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Wnn, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(dnz, onz));
  PetscFunctionReturn(0);
}

/* W_nn, the normal components' sub-block: from the blocks of a BAIJ W, or MatCreateSubMatrix of an AIJ W. */
static PetscErrorCode NormalSubmatrix(KergsPredictor p, KergsContacts contacts, KergsOperators ops, Mat *Wnn)
{
  PetscInt *rows;
  IS        is;
  PetscBool blocked;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)ops->W, &blocked, MATSEQBAIJ, MATMPIBAIJ, ""));
  if (blocked) {
    PetscCall(NormalFromBlocks(ops->W, ops->ncomp, Wnn));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc1(contacts->n, &rows));
  for (PetscInt k = 0; k < contacts->n; k++) rows[k] = (contacts->start + k) * ops->ncomp;
  PetscCall(ISCreateGeneral(p->comm, contacts->n, rows, PETSC_OWN_POINTER, &is));
  PetscCall(MatCreateSubMatrix(ops->W, is, is, MAT_INITIAL_MATRIX, Wnn));
  PetscCall(ISDestroy(&is));
  PetscFunctionReturn(0);
}

/* W_nn, v^d_n and a warm start r_n (the contacts' normal impulses, >= 0, zero when inactive). With one
   component per contact they are W, v^d and rtilde themselves; otherwise the normal sub-block is extracted. */
static PetscErrorCode NormalProblem(KergsPredictor p, KergsContacts contacts, KergsOperators ops, const PetscBool *active, Vec rtilde,
                                    Mat *Wnn, Vec *vdn, Vec *rn)
{
  PetscScalar       *r;
  const PetscScalar *vd;

  PetscFunctionBeginUser;
  if (ops->ncomp == 1) {
    PetscCall(PetscObjectReference((PetscObject)ops->W));
    PetscCall(PetscObjectReference((PetscObject)ops->vd));
    PetscCall(PetscObjectReference((PetscObject)rtilde));
    *Wnn = ops->W;
    *vdn = ops->vd;
    *rn  = rtilde;
  } else {
    PetscCall(NormalSubmatrix(p, contacts, ops, Wnn));
    PetscCall(MatCreateVecs(*Wnn, rn, vdn));
    PetscCall(VecGetArray(*vdn, &r));
    PetscCall(VecGetArrayRead(ops->vd, &vd));
    for (PetscInt k = 0; k < contacts->n; k++) r[k] = vd[k * ops->ncomp];
    PetscCall(VecRestoreArrayRead(ops->vd, &vd));
    PetscCall(VecRestoreArray(*vdn, &r));
  }
  PetscCall(VecGetArray(*rn, &r));
  for (PetscInt k = 0; k < contacts->n; k++) r[k] = active[k] ? PetscMax(contacts->c[k].r[0], 0.0) : 0.0;
  PetscCall(VecRestoreArray(*rn, &r));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsPredictorPredict_Unilateral(KergsPredictor p, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                                       const PetscBool *active, Vec rtilde)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;
  KergsSweepMeasures    m = {0, 0};
  Mat                   Wnn;
  Vec                   vdn, rn;

  PetscFunctionBeginUser;
  (void)scene;
  PetscCall(NormalProblem(p, contacts, ops, active, rtilde, &Wnn, &vdn, &rn));
  PetscCall(KergsSweepSetUp(u->sweep, Wnn, 1, NULL, active));
  p->converged = PETSC_FALSE;
  for (p->sweeps = 1; p->sweeps <= u->max_it; p->sweeps++) {
    PetscCall(KergsSweepRun(u->sweep, rn, vdn, NULL, NULL, &m));
    if (m.quad < u->tol) {
      p->converged = PETSC_TRUE;
      break;
    }
  }
  p->sweeps = PetscMin(p->sweeps, u->max_it);
  u->quad   = m.quad;
  if (!p->converged)
    PetscCall(PetscInfo(NULL, "unilateral predictor: %" PetscInt_FMT " sweeps without reaching quad < %g (last %g)\n", u->max_it,
                        (double)u->tol, (double)m.quad));
  PetscCall(KergsSweepReset(u->sweep)); /* drop the references to W_nn and to the caller's active array */
  if (ops->ncomp > 1) {
    PetscScalar       *rt;
    const PetscScalar *r;
    PetscCall(VecGetArray(rtilde, &rt));
    PetscCall(VecGetArrayRead(rn, &r));
    for (PetscInt k = 0; k < contacts->n; k++) rt[k * ops->ncomp] = r[k];
    PetscCall(VecRestoreArrayRead(rn, &r));
    PetscCall(VecRestoreArray(rtilde, &rt));
  }
  PetscCall(MatDestroy(&Wnn));
  PetscCall(VecDestroy(&vdn));
  PetscCall(VecDestroy(&rn));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsPredictorView_Unilateral(KergsPredictor p, PetscViewer viewer)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "NLGS on the normal components until quad < %g, at most %" PetscInt_FMT " sweeps (last: %" PetscInt_FMT " sweeps, quad %g)\n",
      (double)u->tol, u->max_it, p->sweeps, (double)u->quad));
  PetscFunctionReturn(0);
}

static PetscErrorCode KergsPredictorDestroy_Unilateral(KergsPredictor p)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;

  PetscFunctionBeginUser;
  PetscCall(KergsSweepDestroy(&u->sweep));
  PetscCall(PetscFree(p->data));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorCreate_Unilateral(KergsPredictor p)
{
  Predictor_Unilateral *u;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&u));
  u->tol    = 1e-10;
  u->max_it = 1000;
  PetscCall(KergsSweepCreate(p->comm, &u->sweep));
  p->data               = u;
  p->ops.setfromoptions = KergsPredictorSetFromOptions_Unilateral;
  p->ops.predict        = KergsPredictorPredict_Unilateral;
  p->ops.view           = KergsPredictorView_Unilateral;
  p->ops.destroy        = KergsPredictorDestroy_Unilateral;
  PetscFunctionReturn(0);
}
