/* The solver object as PETSc's KSP is one: why a solve stopped (KergsSolverConvergedReason, recorded in /stats and printed
   by -solver_converged_reason), and options prefixes that let two solvers of one program take different options. */
static const char help[] = "kergs solver object tests: converged reasons, options prefixes.\n";

#include "testing.h"
#include <unistd.h>

#define CONFINE5 "-options_file cases/confine5.opts -steps 2 "

/* The reason recorded for the last step of a 2-step confine5 run under the given extra options. */
static PetscErrorCode ReasonOf(const char *extra, KergsSolverConvergedReason *reason, PetscReal *converged)
{
  KergsStepper st;
  char         opts[512];
  PetscReal    value;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts), CONFINE5 "%s", extra));
  PetscCall(MakeStepper(opts, &st));
  for (PetscInt s = 0; s < 2; s++) PetscCall(KergsStepperStep(st));
  PetscCall(StatAt(st->results, "converged_reason", -1, &value));
  PetscCall(StatAt(st->results, "converged", -1, converged));
  *reason = (KergsSolverConvergedReason)(PetscInt)value;
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Each reason a type can reach on an ordinary scene, and the converged column agreeing with its sign. */
static PetscErrorCode TestReasons(void)
{
  static const struct {
    const char                *options;
    KergsSolverConvergedReason want;
  } cases[] = {
      {"-solver_type nlgs -solver_criterion quad", KERGS_SOLVER_CONVERGED_QUAD},
      {"-solver_type nlgs -solver_criterion maxm", KERGS_SOLVER_CONVERGED_MAXM},
      {"-solver_type newton -solver_tol 1e-10", KERGS_SOLVER_CONVERGED_NATURAL},
      {"-solver_type nlgs -solver_max_it 1", KERGS_SOLVER_DIVERGED_MAX_IT},
      {"-solver_type newton -solver_max_it 1 -solver_tol 1e-14", KERGS_SOLVER_DIVERGED_MAX_IT},
      /* quad met after a sweep or two, the original problem far from solved */
      {"-solver_type nlgs -solver_tol 0.5 -solver_residual_tol 1e-12", KERGS_SOLVER_DIVERGED_RESIDUAL},
      /* three disks afloat, far from each other and from the walls: no contact in the step */
      {"-solver_type nlgs -disks_x 1,5,2.5,5,4,5 -wall_ceiling_a 6,100 -wall_ceiling_b -1,100 -gravity 0,0",
       KERGS_SOLVER_CONVERGED_NO_CONTACTS},
  };

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
    KergsSolverConvergedReason got;
    PetscReal                  converged;
    PetscCall(ReasonOf(cases[i].options, &got, &converged));
    PetscCall(Checkf((PetscBool)(got == cases[i].want), got, cases[i].want, "%s: reason %s", cases[i].options,
                     KergsSolverConvergedReasons[cases[i].want]));
    PetscCall(Checkf((PetscBool)(converged == (got > 0 ? 1.0 : 0.0)), converged, got > 0, "%s: converged column agrees with the reason",
                     cases[i].options));
  }
  PetscFunctionReturn(0);
}

/* -solver_converged_reason ascii:FILE: one line per solve, naming the reason. */
static PetscErrorCode TestReasonViewer(void)
{
  KergsStepper st;
  char         path[PETSC_MAX_PATH_LEN], opts[PETSC_MAX_PATH_LEN + 128], line[512];
  PetscInt     lines = 0, named = 0;
  PetscMPIInt  rank;
  int          pid = (int)getpid();

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallMPI(MPI_Bcast(&pid, 1, MPI_INT, 0, PETSC_COMM_WORLD));
  PetscCall(PetscSNPrintf(path, sizeof(path), "/tmp/kergs-test-solver-reasons-%d.txt", pid));
  PetscCall(PetscSNPrintf(opts, sizeof(opts), CONFINE5 "-solver_converged_reason ascii:%s", path));
  PetscCall(MakeStepper(opts, &st));
  for (PetscInt s = 0; s < 2; s++) PetscCall(KergsStepperStep(st));
  PetscCall(KergsStepperDestroy(&st)); /* the file closes with the solver's viewer */
  if (rank == 0) {
    FILE *f = fopen(path, "r");
    PetscCheck(f, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "cannot read %s", path);
    while (fgets(line, sizeof(line), f)) {
      lines++;
      if (strstr(line, "converged due to CONVERGED_QUAD in step")) named++;
    }
    fclose(f);
    (void)remove(path);
  }
  PetscCallMPI(MPI_Bcast(&lines, 1, MPIU_INT, 0, PETSC_COMM_WORLD));
  PetscCallMPI(MPI_Bcast(&named, 1, MPIU_INT, 0, PETSC_COMM_WORLD));
  PetscCall(Check((PetscBool)(lines == 2 && named == 2), "-solver_converged_reason: one line per step naming CONVERGED_QUAD", named, 2));
  PetscFunctionReturn(0);
}

/* Two steppers in one program, one of them with the solver prefix b_: each reads its own options, and the prefixed one
   passes its prefix to its inner PETSc solver (-b_solver_ksp_type). */
static PetscErrorCode TestPrefix(void)
{
  KergsStepper    plain, prefixed;
  KergsSolver     solver;
  KergsSolverType type;
  PetscReal       res_plain, res_prefixed, tol;
  PetscInt        max_it;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsClear(NULL));
  PetscCall(PetscOptionsInsertString(NULL, CONFINE5 "-solver_type nlgs -solver_max_it 7 -b_solver_type newton -b_solver_tol 1e-10 "
                                                    "-b_solver_ksp_type preonly -output_none -quiet"));
  PetscCall(KergsStepperCreate(PETSC_COMM_WORLD, &plain));
  PetscCall(KergsStepperSetFromOptions(plain));
  PetscCall(KergsStepperCreate(PETSC_COMM_WORLD, &prefixed));
  PetscCall(KergsStepperGetSolver(prefixed, &solver));
  PetscCall(KergsSolverSetOptionsPrefix(solver, "b_"));
  PetscCall(KergsStepperSetFromOptions(prefixed));
  PetscCall(KergsSolverGetType(solver, &type));
  PetscCall(KergsSolverGetTolerances(solver, &tol, &max_it));
  PetscCall(CheckTrue(PETSC_COMM_WORLD, (PetscBool)(!strcmp(type, KERGS_SOLVER_NEWTON) && tol == 1e-10), "prefix b_: newton to 1e-10"));
  PetscCall(KergsStepperGetSolver(plain, &solver));
  PetscCall(KergsSolverGetType(solver, &type));
  PetscCall(KergsSolverGetTolerances(solver, &tol, &max_it));
  PetscCall(CheckTrue(PETSC_COMM_WORLD, (PetscBool)(!strcmp(type, KERGS_SOLVER_NLGS) && max_it == 7), "no prefix: nlgs, 7 sweeps"));
  PetscCall(KergsStepperStep(plain));
  PetscCall(KergsStepperStep(prefixed));
  PetscCall(StatAt(plain->results, "residual", 0, &res_plain));
  PetscCall(StatAt(prefixed->results, "residual", 0, &res_prefixed));
  PetscCall(Check((PetscBool)(res_prefixed <= 1e-10 && res_plain > 1e-10), "the prefixed solver solves to 1e-10, the plain one does not",
                  res_prefixed, 1e-10));
  {
    PetscBool used;
    PetscCall(PetscOptionsUsed(NULL, "b_solver_ksp_type", &used));
    PetscCall(CheckTrue(PETSC_COMM_WORLD, used, "-b_solver_ksp_type read by the prefixed newton's linear solver"));
  }
  PetscCall(KergsStepperDestroy(&plain));
  PetscCall(KergsStepperDestroy(&prefixed));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(TestReasons());
  PetscCall(TestReasonViewer());
  PetscCall(TestPrefix());
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
