/* kergs predictor: the prediction r~ of the contact impulses in NLKerGS-P (Algorithm 3); the correction pins
   the kernel part of r to that of r~. Types registered by name, chosen with -predictor_type:
     none        r~ = 0
     linear      Algorithm 4, parameter -predictor_eta: unilateral contact regularised, friction ignored
     unilateral  the frictionless unilateral problem solved exactly (NLGS on the normal components)
     elastic     Algorithm 5, parameter -predictor_epsilon: numerical contact stiffness pushing gaps back
   The DOF-space linear systems (M + c H_f D H_f^T) V~ = b are solved with a KSP whose options have the
   prefix predictor_ (default: direct Cholesky, CHOLMOD on one rank, MUMPS on several). D selects the normal
   components of the active contacts (g^- < 0).

   Units (DESIGN.md section 2; impulses in mass x velocity). The linear law r_n = -(dt/eta) v_n makes eta/dt
   a compliance (velocity per impulse, 1/mass) like W_nn; the elastic law r_n = -(dt/eps) g^+ makes 1/eps a
   contact stiffness (force per length), so eps/dt^2 is again a compliance. With -predictor_relative (the
   default) -predictor_eta and -predictor_epsilon are dimensionless and scaled by w, the mean W_nn over the
   active contacts:
     eta_abs = eta dt w          r_n = -v_n / (eta w): the regularised contact is eta times as compliant as a
                                 typical contact; as eta -> 0, r^lin -> the exact bilateral impulses, with an
                                 error of about eta times a factor of the packing (28 eta for a column of 6);
     epsilon_abs = epsilon dt^2 w   one contact alone closes the fraction W_nn / (W_nn + epsilon w) of its
                                 interpenetration in one step (epsilon -> 0: all of it; 1: about half);
   with -predictor_relative 0 they are taken as they are, in s/kg and s^2/kg (the paper's eta and epsilon).
   Defaults: eta = 1e-6 (close to the bilateral limit, K's condition number about 1e6); epsilon = 1 (the
   contact oscillates with a period of about 2 pi steps, resolved: no micro-rebounds; half the gap per step).
   Extremes: r~ is finite for any eta, epsilon > 0 (tested down to 1e-12); K's condition number grows as
   1/eta (1/epsilon), harmless for the direct solver, not for CG. Algorithm 4/5's form r~ = -(q + c A V~)
   cancels as c grows where V~ closes gaps, so r~ then carries a relative rounding error of about
   1e-16 / epsilon (relative epsilon; 3e-5 for one disk at 1e-12); the equations themselves hold to rounding. */
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

PETSC_EXTERN PetscErrorCode KergsPredictorRegister(const char[], PetscErrorCode (*)(KergsPredictor));
PETSC_EXTERN PetscErrorCode KergsPredictorCreate(MPI_Comm, KergsPredictor *);
PETSC_EXTERN PetscErrorCode KergsPredictorSetType(KergsPredictor, KergsPredictorType);
PETSC_EXTERN PetscErrorCode KergsPredictorSetFromOptions(KergsPredictor);
/* r~ over all contact components (layout of ops->r); tangential components are zero. Collective.
   active: per local contact (the solver's array); NULL: active when g^- <= 0 (the paper's gap rule).
   Inactive contacts get r~ = 0. Nothing is solved when no contact is active. */
PETSC_EXTERN PetscErrorCode KergsPredictorPredict(KergsPredictor, KergsScene, KergsContacts, KergsOperators, const PetscBool *active,
                                                  Vec rtilde);
PETSC_EXTERN PetscErrorCode KergsPredictorView(KergsPredictor, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsPredictorDestroy(KergsPredictor *);

PETSC_EXTERN PetscErrorCode KergsPredictorCreate_None(KergsPredictor);
PETSC_EXTERN PetscErrorCode KergsPredictorCreate_Linear(KergsPredictor);
PETSC_EXTERN PetscErrorCode KergsPredictorCreate_Unilateral(KergsPredictor);
PETSC_EXTERN PetscErrorCode KergsPredictorCreate_Elastic(KergsPredictor);

/* Shared by the types. */
/* Create p->ksp (prefix predictor_) with the direct default; KergsPredictorSetFromOptions then reads its options. */
PETSC_EXTERN PetscErrorCode KergsPredictorCreateKSP(KergsPredictor);
/* The regularised prediction of Algorithms 4 and 5, with A = D H_f^T (the active normal rows of H_f^T):
     (M + c A^T A) V~ = R^d + M V_f^- - A^T q,   r~_n = -(q + c A V~) on the active normal components.
   q: over all contact components (layout of ops->r), only its active normal entries are read.
   Sets p->Vtilde, p->ksp_its, p->converged; rtilde's other components are left untouched. Collective. */
PETSC_EXTERN PetscErrorCode KergsPredictorSolveRegularised(KergsPredictor, KergsContacts, KergsOperators, const PetscBool *active,
                                                           PetscReal c, Vec q, Vec rtilde);

#endif
