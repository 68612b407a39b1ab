/* kergs predictor type "linear": Algorithm 4. The unilateral law of the active contacts is replaced by the
   linear relation r_n = -(dt/eta) v_n (eq. 3), friction is ignored:
     (M + (dt/eta) H_f D H_f^T) V~_f = R^d + M V_f^- - (dt/eta) H_f D H_g^T V_g^+
     r^lin = -(dt/eta) D (H_f^T V~_f + H_g^T V_g^+)
   Units: eta in s/kg, so that dt/eta is a mass (predictor.h); by default -predictor_eta is relative. */
#include <kergs/private/predictorimpl.h>

static PetscErrorCode PredictorPredict_Linear(KergsPredictor p, const KergsPredictorInput *in, const PetscBool *active, Vec rtilde)
{
  const PetscReal c = in->dt / p->eta_abs;
  Vec             q;

  PetscFunctionBeginUser;
  /* q = (dt/eta) H_g^T V_g^+ (the driven walls' part of v~), zero without driven walls */
  PetscCall(VecDuplicate(rtilde, &q));
  if (in->HgT) {
    PetscCall(MatMult(in->HgT, in->Vg, q));
    PetscCall(VecScale(q, c));
  } else
    PetscCall(VecZeroEntries(q));
  PetscCall(KergsPredictorSolveRegularised(p, in, active, c, q, rtilde));
  PetscCall(VecDestroy(&q));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorView_Linear(KergsPredictor p, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  if (p->relative)
    PetscCall(PetscViewerASCIIPrintf(viewer, "eta %g relative to dt * mean W_nn (last: %g s/kg)\n", (double)p->eta, (double)p->eta_abs));
  else
    PetscCall(PetscViewerASCIIPrintf(viewer, "eta %g s/kg\n", (double)p->eta));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorCreate_Linear(KergsPredictor p)
{
  PetscFunctionBeginUser;
  p->ops.predict = PredictorPredict_Linear;
  p->ops.view    = PredictorView_Linear;
  PetscCall(KergsPredictorCreateKSP(p));
  PetscFunctionReturn(0);
}
