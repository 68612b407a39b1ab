/* kergs predictor: the prediction r~ of the contact impulses in NLKerGS-P (Algorithm 3); the correction pins
   the kernel part of r to that of r~. Types registered by name, chosen with -predictor_type:
     none        r~ = 0
     linear      Algorithm 4, parameter -predictor_eta: unilateral contact regularised, friction ignored
     unilateral  the frictionless unilateral problem solved exactly (NLGS on the normal components)
     elastic     Algorithm 5, parameter -predictor_epsilon: numerical contact stiffness pushing gaps back
   The DOF-space linear systems (M + c H_f D H_f^T) V~ = b are solved with a KSP whose options have the
   prefix predictor_ (default: direct Cholesky, CHOLMOD on one rank, MUMPS on several). D selects the normal
   components of the active contacts (g^- < 0). */
#ifndef KERGS_PREDICTOR_H
#define KERGS_PREDICTOR_H

#include <kergs/operators.h>
#include <petscksp.h>

typedef const char *KergsPredictorType;
#define KERGS_PREDICTOR_NONE       "none"
#define KERGS_PREDICTOR_LINEAR     "linear"
#define KERGS_PREDICTOR_UNILATERAL "unilateral"
#define KERGS_PREDICTOR_ELASTIC    "elastic"

typedef struct _p_KergsPredictor *KergsPredictor;
typedef struct {
  PetscErrorCode (*setfromoptions)(KergsPredictor, PetscOptionItems *);
  PetscErrorCode (*predict)(KergsPredictor, KergsScene, KergsContacts, KergsOperators, const PetscBool *active, Vec rtilde);
  PetscErrorCode (*view)(KergsPredictor, PetscViewer);
  PetscErrorCode (*destroy)(KergsPredictor);
} KergsPredictorOps;

struct _p_KergsPredictor {
  MPI_Comm          comm;
  char              type[64];
  KergsPredictorOps ops;
  void             *data;
  PetscReal         eta;     /* -predictor_eta (linear) */
  PetscReal         epsilon; /* -predictor_epsilon (elastic) */
  KSP               ksp;     /* DOF-space solver, prefix predictor_ */
  PetscInt          ksp_its; /* iterations of the last solve (0 for direct) */
  PetscReal         seconds; /* time of the last prediction */
};

PETSC_EXTERN PetscErrorCode KergsPredictorRegister(const char[], PetscErrorCode (*)(KergsPredictor));
PETSC_EXTERN PetscErrorCode KergsPredictorCreate(MPI_Comm, KergsPredictor *);
PETSC_EXTERN PetscErrorCode KergsPredictorSetType(KergsPredictor, KergsPredictorType);
PETSC_EXTERN PetscErrorCode KergsPredictorSetFromOptions(KergsPredictor);
/* r~ over all contact components (layout of ops->r); tangential components are zero. Collective. */
PETSC_EXTERN PetscErrorCode KergsPredictorPredict(KergsPredictor, KergsScene, KergsContacts, KergsOperators, const PetscBool *active, Vec rtilde);
PETSC_EXTERN PetscErrorCode KergsPredictorView(KergsPredictor, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsPredictorDestroy(KergsPredictor *);

PETSC_EXTERN PetscErrorCode KergsPredictorCreate_None(KergsPredictor);
PETSC_EXTERN PetscErrorCode KergsPredictorCreate_Linear(KergsPredictor);
PETSC_EXTERN PetscErrorCode KergsPredictorCreate_Unilateral(KergsPredictor);
PETSC_EXTERN PetscErrorCode KergsPredictorCreate_Elastic(KergsPredictor);

#endif
