/* kergs predictor type "none": r~ = 0 (Algorithm 3 without prediction; the correction then pins the kernel
   part of r to zero). */
#include <kergs/private/predictorimpl.h>

static PetscErrorCode PredictorPredict_None(KergsPredictor p, const KergsPredictorInput *in, const PetscBool *active, Vec rtilde)
{
  PetscFunctionBeginUser;
  (void)p;
  (void)in;
  (void)active;
  PetscCall(VecZeroEntries(rtilde));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorView_None(KergsPredictor p, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  (void)p;
  PetscCall(PetscViewerASCIIPrintf(viewer, "r~ = 0\n"));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorCreate_None(KergsPredictor p)
{
  PetscFunctionBeginUser;
  p->ops.predict = PredictorPredict_None;
  p->ops.view    = PredictorView_None;
  PetscFunctionReturn(0);
}
