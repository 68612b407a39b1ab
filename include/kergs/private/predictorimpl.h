/* kergs predictor, private: the predictor object and its operations, for src/solver/predictor.c and the types in
   src/solver/predictors/ (as PETSc's KSP types use kspimpl.h); other components go through kergs/predictor.h. */
#ifndef KERGS_PREDICTORIMPL_H
#define KERGS_PREDICTORIMPL_H

#include <kergs/predictor.h>

/* What a prediction reads from the scene, the contacts and the operators (fetched through their accessors by
   KergsPredictorPredict). */
typedef struct {
  PetscReal      dt, theta;
  PetscInt       ncontacts, start; /* owned contacts, global index of the first */
  KergsContact  *c;
  KergsDofLayout L;
  Mat            HfT, HgT, W;
  Vec            r, vd, Vf, Minv, Rd, Vg;
} KergsPredictorInput;

/* The operations of a type. setfromoptions is called inside the predictor's options block, as PETSc's types do. */
typedef struct {
  PetscErrorCode (*setfromoptions)(PetscOptionItems *, KergsPredictor);
  PetscErrorCode (*predict)(KergsPredictor, const KergsPredictorInput *, const PetscBool *active, Vec rtilde);
  PetscErrorCode (*view)(KergsPredictor, PetscViewer);
  PetscErrorCode (*destroy)(KergsPredictor);
} KergsPredictorOps;

struct _p_KergsPredictor {
  MPI_Comm          comm;
  char              prefix[256]; /* options prefix (KergsPredictorSetOptionsPrefix), before predictor_ */
  char              type[64];
  KergsPredictorOps ops;
  void             *data;
  PetscReal         eta;         /* -predictor_eta (linear) */
  PetscReal         epsilon;     /* -predictor_epsilon (elastic) */
  KSP               ksp;         /* DOF-space solver, prefix predictor_ */
  PetscInt          ksp_its;     /* iterations of the last solve (0 for direct) */
  PetscReal         seconds;     /* time of the last prediction */
  PetscBool         relative;    /* -predictor_relative: eta and epsilon relative to the mean W_nn (above) */
  PetscReal         wmean;       /* last prediction: mean W_nn over the active contacts (1/mass; 1 if none) */
  PetscReal         eta_abs;     /* last prediction: eta in s/kg (dt/eta_abs multiplies velocities) */
  PetscReal         epsilon_abs; /* last prediction: epsilon in s^2/kg */
  PetscInt          nactive;     /* last prediction: active contacts (global) */
  PetscInt          sweeps;      /* last prediction (unilateral): NLGS sweeps */
  PetscBool         converged;   /* last prediction: the KSP or the unilateral NLGS reached its tolerance */
  Vec               Vtilde;      /* last prediction (linear, elastic): V~_f; NULL when no system was solved */
};

PETSC_INTERN PetscErrorCode KergsPredictorCreate_None(KergsPredictor);
PETSC_INTERN PetscErrorCode KergsPredictorCreate_Linear(KergsPredictor);
PETSC_INTERN PetscErrorCode KergsPredictorCreate_Unilateral(KergsPredictor);
PETSC_INTERN PetscErrorCode KergsPredictorCreate_Elastic(KergsPredictor);

/* Shared by the types. */
/* Create p->ksp (prefix predictor_) with the direct default; KergsPredictorSetFromOptions then reads its options. */
PETSC_INTERN PetscErrorCode KergsPredictorCreateKSP(KergsPredictor);
/* The regularised prediction of Algorithms 4 and 5, with A = D H_f^T (the active normal rows of H_f^T):
     (M + c A^T A) V~ = R^d + M V_f^- - A^T q,   r~_n = -(q + c A V~) on the active normal components.
   q: over all contact components (layout of ops->r), only its active normal entries are read.
   Sets p->Vtilde, p->ksp_its, p->converged; rtilde's other components are left untouched. Collective. */
PETSC_INTERN PetscErrorCode KergsPredictorSolveRegularised(KergsPredictor, const KergsPredictorInput *, const PetscBool *active,
                                                           PetscReal c, Vec q, Vec rtilde);

#endif
