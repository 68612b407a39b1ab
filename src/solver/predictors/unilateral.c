/* kergs predictor type "unilateral": the frictionless unilateral problem solved exactly on the normal
   components of the active contacts (the paper's "prédicteur unilatéral", section 3), no parameter:
     v_n = W_nn r_n + v^d_n,   0 <= v_n _|_ r_n >= 0 (active),   r_n = 0 (inactive),
   by NLGS sweeps (include/kergs/sweep.h, one component per contact, mu = 0) on the normal sub-block W_nn of W,
   warm-started from the contacts' impulses, until the W-weighted change quad < -predictor_unilateral_tol or
   -predictor_unilateral_max_it sweeps. Without friction in the scene W_nn is W itself. */
#include <kergs/private/predictorimpl.h>
#include <kergs/sweep.h>

typedef struct {
  PetscReal  tol;
  PetscInt   max_it;
  KergsSweep sweep;
  PetscReal  quad; /* last sweep's quad */
} Predictor_Unilateral;

static PetscErrorCode PredictorSetFromOptions_Unilateral(PetscOptionItems *PetscOptionsObject, KergsPredictor p)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "Unilateral predictor (exact frictionless problem, NLGS)");
  PetscCall(PetscOptionsReal("-predictor_unilateral_tol",
                             "Stop the NLGS sweeps when the W-weighted relative change of r_n (quad) is below this", "", u->tol, &u->tol,
                             NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-predictor_unilateral_max_it", "Maximum number of NLGS sweeps of the unilateral predictor",
                            "", u->max_it, &u->max_it, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(u->tol > 0 && PetscIsNormalReal(u->tol), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-predictor_unilateral_tol %g must be a positive finite number", (double)u->tol);
  PetscCheck(u->max_it >= 1, p->comm, PETSC_ERR_ARG_OUTOFRANGE, "-predictor_unilateral_max_it %" PetscInt_FMT " must be at least 1",
             u->max_it);
  PetscFunctionReturn(0);
}

/* The entries (W_alpha,beta)_nn of W's local normal rows (alpha nc) in the normal columns (beta nc), read row by
   row from any storage of W (upper rows only for SBAIJ): counted into dnz/onz (columns of this rank's contacts or
   not) when dnz is given, set into Wnn otherwise. */
static PetscErrorCode NormalEntries(Mat W, PetscInt nc, Mat Wnn, PetscInt *dnz, PetscInt *onz)
{
  PetscInt           rstart, rend, ncols, row, col;
  const PetscInt    *cols;
  const PetscScalar *vals;

  PetscFunctionBeginUser;
  PetscCall(MatGetOwnershipRange(W, &rstart, &rend));
  for (PetscInt i = rstart; i < rend; i += nc) {
    row = i / nc;
    PetscCall(MatGetRow(W, i, &ncols, &cols, &vals));
    for (PetscInt k = 0; k < ncols; k++) {
      if (cols[k] % nc) continue;
      col = cols[k] / nc;
      if (!dnz)
        PetscCall(MatSetValues(Wnn, 1, &row, 1, &col, &vals[k], INSERT_VALUES));
      else if (cols[k] >= rstart && cols[k] < rend)
        dnz[row - rstart / nc]++;
      else
        onz[row - rstart / nc]++;
    }
    PetscCall(MatRestoreRow(W, i, &ncols, &cols, &vals));
  }
  PetscFunctionReturn(0);
}

/* W_nn, the normal components' sub-block, contact alpha being row and column alpha; stored like W: by its upper
   triangle (SBAIJ, block size 1) when W is, so that the sweep streams half of it, AIJ otherwise. */
static PetscErrorCode NormalSubmatrix(const KergsPredictorInput *in, Mat *Wnn)
{
  const PetscInt nc = in->L.ncomp;
  PetscInt       m, n, *dnz, *onz;
  PetscBool      upper;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)in->W, &upper, MATSEQSBAIJ, MATMPISBAIJ, ""));
  PetscCall(MatGetLocalSize(in->W, &m, NULL));
  n = m / nc;
  PetscCall(PetscCalloc2(n + 1, &dnz, n + 1, &onz));
  PetscCall(MatGetRowUpperTriangular(in->W)); /* MatGetRow on SBAIJ: the stored (upper) part of each row */
  PetscCall(NormalEntries(in->W, nc, NULL, dnz, onz));
  PetscCall(MatCreate(PetscObjectComm((PetscObject)in->W), Wnn));
  PetscCall(MatSetSizes(*Wnn, n, n, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetType(*Wnn, upper ? MATSBAIJ : MATAIJ));
  PetscCall(MatXAIJSetPreallocation(*Wnn, 1, dnz, onz, dnz, onz));
  PetscCall(MatSetOption(*Wnn, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(NormalEntries(in->W, nc, *Wnn, NULL, NULL));
  PetscCall(MatRestoreRowUpperTriangular(in->W));
  PetscCall(MatAssemblyBegin(*Wnn, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Wnn, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(dnz, onz));
  PetscFunctionReturn(0);
}

/* W_nn, v^d_n and a warm start r_n (the contacts' normal impulses, >= 0, zero when inactive). With one
   component per contact they are W, v^d and rtilde themselves; otherwise the normal sub-block is extracted. */
static PetscErrorCode NormalProblem(const KergsPredictorInput *in, const PetscBool *active, Vec rtilde, Mat *Wnn, Vec *vdn, Vec *rn)
{
  PetscScalar       *r;
  const PetscScalar *vd;

  PetscFunctionBeginUser;
  if (in->L.ncomp == 1) {
    PetscCall(PetscObjectReference((PetscObject)in->W));
    PetscCall(PetscObjectReference((PetscObject)in->vd));
    PetscCall(PetscObjectReference((PetscObject)rtilde));
    *Wnn = in->W;
    *vdn = in->vd;
    *rn  = rtilde;
  } else {
    PetscCall(NormalSubmatrix(in, Wnn));
    PetscCall(MatCreateVecs(*Wnn, rn, vdn));
    PetscCall(VecGetArray(*vdn, &r));
    PetscCall(VecGetArrayRead(in->vd, &vd));
    for (PetscInt k = 0; k < in->ncontacts; k++) r[k] = vd[k * in->L.ncomp];
    PetscCall(VecRestoreArrayRead(in->vd, &vd));
    PetscCall(VecRestoreArray(*vdn, &r));
  }
  PetscCall(VecGetArray(*rn, &r));
  for (PetscInt k = 0; k < in->ncontacts; k++) r[k] = active[k] ? PetscMax(in->c[k].r[0], 0.0) : 0.0;
  PetscCall(VecRestoreArray(*rn, &r));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorPredict_Unilateral(KergsPredictor p, const KergsPredictorInput *in, const PetscBool *active, Vec rtilde)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;
  KergsSweepMeasures    m = {0, 0};
  Mat                   Wnn;
  Vec                   vdn, rn;

  PetscFunctionBeginUser;
  PetscCall(NormalProblem(in, active, rtilde, &Wnn, &vdn, &rn));
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
  if (in->L.ncomp > 1) {
    PetscScalar       *rt;
    const PetscScalar *r;
    PetscCall(VecGetArray(rtilde, &rt));
    PetscCall(VecGetArrayRead(rn, &r));
    for (PetscInt k = 0; k < in->ncontacts; k++) rt[k * in->L.ncomp] = r[k];
    PetscCall(VecRestoreArrayRead(rn, &r));
    PetscCall(VecRestoreArray(rtilde, &rt));
  }
  PetscCall(MatDestroy(&Wnn));
  PetscCall(VecDestroy(&vdn));
  PetscCall(VecDestroy(&rn));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorView_Unilateral(KergsPredictor p, PetscViewer viewer)
{
  Predictor_Unilateral *u = (Predictor_Unilateral *)p->data;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "NLGS on the normal components until quad < %g, at most %" PetscInt_FMT " sweeps (last: %" PetscInt_FMT " sweeps, quad %g)\n",
      (double)u->tol, u->max_it, p->sweeps, (double)u->quad));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorDestroy_Unilateral(KergsPredictor p)
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
  p->ops.setfromoptions = PredictorSetFromOptions_Unilateral;
  p->ops.predict        = PredictorPredict_Unilateral;
  p->ops.view           = PredictorView_Unilateral;
  p->ops.destroy        = PredictorDestroy_Unilateral;
  PetscFunctionReturn(0);
}
