/* kergs predictor type "elastic": Algorithm 5. Each active contact gets a numerical stiffness 1/eps acting
   on its gap at the end of the step, g^+ = g^- + dt v~_n:
     (M + (dt^2/eps) H_f D H_f^T) V~_f = R^d + M V_f^- - (dt/eps) H_f D (g^- + dt H_g^T V_g^+)
     r^elas = -(dt/eps) D (g^- + dt (H_f^T V~_f + H_g^T V_g^+))
   Dimensions: with r an impulse (kg m/s), g a length and eps in s^2/kg, every term of both lines is an
   impulse: the printed algorithm is consistent (dt/eps: kg/s, dt^2/eps: kg). It is the momentum balance
   M (V~ - V^-) = R^d + H_f r with r = -(dt/eps) D g^+ substituted.
   theta-method (Algorithm 1): free bodies move by dt (theta V^+ + (1 - theta) V^-), driven walls by dt V_g^+,
   so the end-of-step gap (linearised, frames fixed over the step) is
     g^+ = g^- + dt ((1 - theta) H_f^T V_f^- + theta H_f^T V~_f + H_g^T V_g^+) = g^- + dt ((1 - theta) v^- + theta v~)
   with v^- = H_f^T V_f^- + H_g^T V_g^+ and v~ = H_f^T V~_f + H_g^T V_g^+. The paper uses theta = 1,
   where this is Algorithm 5 exactly; for theta < 1 the system is
     (M + theta (dt^2/eps) H_f D H_f^T) V~ = R^d + M V^- - (dt/eps) H_f D (g^- + (1 - theta) dt v^- + theta dt H_g^T V_g^+). */
#include <kergs/private/predictorimpl.h>

static PetscErrorCode PredictorPredict_Elastic(KergsPredictor p, const KergsPredictorInput *in, const PetscBool *active, Vec rtilde)
{
  const PetscReal    dt = in->dt, th = in->theta, k = dt / p->epsilon_abs;
  Vec                q, vminus;
  PetscScalar       *qa;
  const PetscScalar *vm;

  PetscFunctionBeginUser;
  /* q = (dt/eps) (g^- + (1 - theta) dt v^- + theta dt H_g^T V_g^+) on the normal components */
  PetscCall(VecDuplicate(rtilde, &q));
  PetscCall(VecDuplicate(rtilde, &vminus));
  if (in->HgT)
    PetscCall(MatMult(in->HgT, in->Vg, q));
  else
    PetscCall(VecZeroEntries(q));
  PetscCall(MatMultAdd(in->HfT, in->Vf, q, vminus)); /* v^- = H_f^T V_f^- + H_g^T V_g^+ */
  PetscCall(VecGetArray(q, &qa));
  PetscCall(VecGetArrayRead(vminus, &vm));
  for (PetscInt a = 0; a < in->ncontacts; a++) {
    const PetscInt i = a * in->L.ncomp;
    qa[i]            = k * (in->c[a].gap + (1.0 - th) * dt * vm[i] + th * dt * qa[i]);
  }
  PetscCall(VecRestoreArrayRead(vminus, &vm));
  PetscCall(VecRestoreArray(q, &qa));
  PetscCall(VecDestroy(&vminus));
  PetscCall(KergsPredictorSolveRegularised(p, in, active, th * dt * k, q, rtilde));
  PetscCall(VecDestroy(&q));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorView_Elastic(KergsPredictor p, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  if (p->relative)
    PetscCall(PetscViewerASCIIPrintf(viewer, "epsilon %g relative to dt^2 * mean W_nn (last: %g s^2/kg)\n", (double)p->epsilon,
                                     (double)p->epsilon_abs));
  else
    PetscCall(PetscViewerASCIIPrintf(viewer, "epsilon %g s^2/kg\n", (double)p->epsilon));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorCreate_Elastic(KergsPredictor p)
{
  PetscFunctionBeginUser;
  p->ops.predict = PredictorPredict_Elastic;
  p->ops.view    = PredictorView_Elastic;
  PetscCall(KergsPredictorCreateKSP(p));
  PetscFunctionReturn(0);
}
