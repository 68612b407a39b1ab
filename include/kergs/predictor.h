/* kergs predictor: the prediction r~ of the contact impulses in NLKerGS-P (Algorithm 3); the correction pins
   the kernel part of r to that of r~. Types registered by name, chosen with -predictor_type:
     none        r~ = 0
     linear      Algorithm 4, parameter -predictor_eta: unilateral contact regularised, friction ignored
     unilateral  the frictionless unilateral problem solved exactly (NLGS on the normal components)
     elastic     Algorithm 5, parameter -predictor_epsilon: numerical contact stiffness pushing gaps back
   The DOF-space linear systems (M + c H_f D H_f^T) V~ = b are solved with a KSP whose options have the
   prefix predictor_ (default: direct Cholesky, CHOLMOD on one rank, MUMPS on several). D selects the normal
   components of the active contacts (the solver's active set, predicted gap <= 0; g^- <= 0 without one).

   Units (impulses in mass x velocity). The linear law r_n = -(dt/eta) v_n makes eta/dt
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
#define KERGS_PREDICTOR_NONE "none"
#define KERGS_PREDICTOR_LINEAR "linear"
#define KERGS_PREDICTOR_UNILATERAL "unilateral"
#define KERGS_PREDICTOR_ELASTIC "elastic"

typedef struct _p_KergsPredictor *KergsPredictor;

PETSC_EXTERN PetscErrorCode KergsPredictorRegister(const char[], PetscErrorCode (*)(KergsPredictor));
PETSC_EXTERN PetscErrorCode KergsPredictorCreate(MPI_Comm, KergsPredictor *);
PETSC_EXTERN PetscErrorCode KergsPredictorSetType(KergsPredictor, KergsPredictorType);
PETSC_EXTERN PetscErrorCode KergsPredictorSetFromOptions(KergsPredictor);
/* Its options become -<prefix>predictor_... (the owning solver's prefix) */
PETSC_EXTERN PetscErrorCode KergsPredictorSetOptionsPrefix(KergsPredictor, const char[]);
/* r~ over all contact components (layout of ops->r); tangential components are zero. Collective.
   active: per local contact (the solver's array); NULL: active when g^- <= 0 (the paper's gap rule).
   Inactive contacts get r~ = 0. Nothing is solved when no contact is active. */
PETSC_EXTERN PetscErrorCode KergsPredictorPredict(KergsPredictor, KergsScene, KergsContacts, KergsOperators, const PetscBool *active,
                                                  Vec rtilde);
PETSC_EXTERN PetscErrorCode KergsPredictorView(KergsPredictor, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsPredictorDestroy(KergsPredictor *);

/* What the last prediction found and cost (KergsPredictorGetStats). */
typedef struct {
  const char *type;        /* the predictor type */
  PetscReal   seconds;     /* time of the prediction */
  PetscInt    ksp_its;     /* iterations of the DOF-space solve (0 for a direct solve) */
  PetscInt    sweeps;      /* unilateral: NLGS sweeps */
  PetscBool   converged;   /* the KSP or the unilateral NLGS reached its tolerance */
  PetscInt    nactive;     /* active contacts (global) */
  PetscReal   eta_abs;     /* eta used, in s/kg */
  PetscReal   epsilon_abs; /* epsilon used, in s^2/kg */
} KergsPredictorStats;
PETSC_EXTERN PetscErrorCode KergsPredictorGetStats(KergsPredictor, KergsPredictorStats *);

#endif
