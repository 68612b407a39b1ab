/* kergs stepper: the time loop of Algorithm 1 (Moreau-Jean, theta-method):
   detect -> assemble -> solve -> V_f^+ = V_f^- + M^-1 (H_f r + R^d), x^+ = x^- + dt (theta V^+ + (1-theta) V^-)
   -> statistics and snapshots. */
#ifndef KERGS_STEPPER_H
#define KERGS_STEPPER_H

#include <kergs/solver.h>
#include <kergs/results.h>
#include <kergs/partition.h>

typedef struct _p_KergsStepper *KergsStepper;

PETSC_EXTERN PetscErrorCode KergsStepperCreate(MPI_Comm, KergsStepper *);
PETSC_EXTERN PetscErrorCode KergsStepperSetFromOptions(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperStep(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperRun(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperDestroy(KergsStepper *);

/* Accessors: the objects a time step works on (owned by the stepper). */
PETSC_EXTERN PetscErrorCode KergsStepperGetScene(KergsStepper, KergsScene *);
PETSC_EXTERN PetscErrorCode KergsStepperGetContacts(KergsStepper, KergsContacts *);
PETSC_EXTERN PetscErrorCode KergsStepperGetOperators(KergsStepper, KergsOperators *);
PETSC_EXTERN PetscErrorCode KergsStepperGetSolver(KergsStepper, KergsSolver *);
PETSC_EXTERN PetscErrorCode KergsStepperGetResults(KergsStepper, KergsResults *);
PETSC_EXTERN PetscErrorCode KergsStepperGetPartition(KergsStepper, KergsPartition *);
/* Over the run so far: steps whose solve did not converge, and the largest interpenetration seen */
PETSC_EXTERN PetscErrorCode KergsStepperGetRunSummary(KergsStepper, PetscInt *nonconverged, PetscReal *max_violation);

#endif
