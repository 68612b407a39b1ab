/* Solver type "snesvi" (src/solver/solvers/snesvi.c, PETSc's SNESVI on the law written as a complementarity problem):
   one-contact cases (open, stick, stick and slip on a slope) solved to 1e-10 with the right physics, and frictionless
   confine500 (the linear complementarity problem of the normal impulses, W singular) solved to 1e-10 with the
   velocities of the newton type. Run for the SNESVI type given by -test_snes_type (tests/snesvi.cmake). */
static const char help[] = "kergs snesvi solver tests.\n";

#include "testing.h"

#define ONE_DISK "-gravity 0,-10 -dt 1e-3 -disks_source list -disks_radius 0.1 -alert 0.01 -solver_type snesvi -solver_tol 1e-10 "

/* One disk and one wall: open (moving away), resting (closing, stick), on a slope below and above tan = mu (stick,
   slip; rotation locked). Every step converged to 1e-10, and the physics right: at rest, or sliding down at
   g (sin - mu cos). */
static PetscErrorCode TestOneContact(const char *type)
{
  struct {
    const char *what, *opts;
  } cases[] = {
      {"open (the disk leaves the floor)",
       ONE_DISK "-friction 0.5 -disks_x 0,0.1 -disks_velocity 0,5 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      {"stick (the disk rests on the floor)",
       ONE_DISK "-friction 0.5 -disks_x 0,0.0999999 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      {"stick on a slope (tan 0.31 < mu 0.5)",
       ONE_DISK "-friction 0.5 -disks_lock_rotation -disks_x -0.029552,0.095534 -walls slope -wall_slope_a -9.553365,-2.955202 "
                "-wall_slope_b 9.553365,2.955202 -wall_slope_infinite"},
      {"slip on a slope (tan 0.84 > mu 0.5)",
       ONE_DISK "-friction 0.5 -disks_lock_rotation -disks_x -0.064422,0.076484 -walls slope -wall_slope_a -7.648422,-6.442177 "
                "-wall_slope_b 7.648422,6.442177 -wall_slope_infinite"},
  };

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
    PetscInt     maxits, nconv;
    PetscReal    maxres, v[KERGS_DIM];
    KergsStepper st;
    char         opts[1024];
    PetscCall(PetscSNPrintf(opts, sizeof(opts), "%s -steps 5 -solver_snes_type %s", cases[i].opts, type));
    PetscCall(RunSteps(opts, 5, &st, &maxits, &maxres, &nconv));
    PetscCall(Checkf((PetscBool)(nconv == 5 && maxres <= 1e-10), maxres, 1e-10, "%s, one contact, %s: 5 steps converged (largest residual)",
                     type, cases[i].what));
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->v, KERGS_DIM, v));
    if (i == 0)
      PetscCall(Checkf((PetscBool)(v[1] > 4.9), v[1], 4.95, "%s, one contact, %s: flies off, only gravity slows it", type, cases[i].what));
    if (i == 1 || i == 2)
      PetscCall(Checkf((PetscBool)(PetscAbsReal(v[0]) + PetscAbsReal(v[1]) < 1e-9), PetscAbsReal(v[0]) + PetscAbsReal(v[1]), 0,
                       "%s, one contact, %s: at rest", type, cases[i].what));
    if (i == 3) { /* slides down at g (sin - mu cos), 5 steps */
      const PetscReal a = 0.7, want = 10 * (PetscSinReal(a) - 0.5 * PetscCosReal(a)) * 5e-3,
                      got = -(v[0] * PetscCosReal(a) + v[1] * PetscSinReal(a));
      PetscCall(Checkf((PetscBool)(PetscAbsReal(got - want) < 1e-6 * want), got, want, "%s, one contact, %s: slides at g(sin - mu cos)",
                       type, cases[i].what));
    }
    PetscCall(KergsStepperDestroy(&st));
  }
  PetscFunctionReturn(0);
}

/* The disks' velocities (unique without friction, whatever the kernel part of r), gathered by grain id. */
static PetscErrorCode Velocities(KergsStepper st, PetscReal **v)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(KERGS_DIM * st->scene->ndisks, v));
  PetscCall(GatherById(st->scene, st->scene->v, KERGS_DIM, *v));
  PetscFunctionReturn(0);
}

/* Frictionless confine500, 2 steps: the MCP is the linear complementarity problem of the normal impulses, W singular;
   solved to 1e-10 in at most 20 SNES iterations a step (5-15 measured), with newton's velocities (unique without
   friction, whatever the kernel part of r). */
static PetscErrorCode TestFrictionless(const char *type)
{
  KergsStepper a, b;
  PetscInt     maxits, nconv, itsb, nconvb;
  PetscReal    maxres, resb, *va, *vb, diff = 0, scale = 0;
  char         opts[1024];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(
      opts, sizeof(opts),
      "-options_file cases/confine500.opts -friction 0 -steps 2 -solver_type snesvi -solver_tol 1e-10 -solver_snes_type %s", type));
  PetscCall(RunSteps(opts, 2, &a, &maxits, &maxres, &nconv));
  PetscCall(
      Checkf((PetscBool)(nconv == 2 && maxres <= 1e-10), maxres, 1e-10, "frictionless confine500, %s: 2 steps converged (residual)", type));
  PetscCall(Checkf((PetscBool)(maxits <= 20), maxits, 20, "frictionless confine500, %s: at most 20 SNES iterations a step", type));
  PetscCall(RunSteps("-options_file cases/confine500.opts -friction 0 -steps 2 -solver_type newton -solver_tol 1e-12", 2, &b, &itsb, &resb,
                     &nconvb));
  PetscCall(Velocities(a, &va));
  PetscCall(Velocities(b, &vb));
  for (PetscInt i = 0; i < KERGS_DIM * a->scene->ndisks; i++) {
    diff  = PetscMax(diff, PetscAbsReal(va[i] - vb[i]));
    scale = PetscMax(scale, PetscAbsReal(vb[i]));
  }
  PetscCall(Checkf((PetscBool)(nconvb == 2 && diff <= 1e-7 * scale), diff / scale, 1e-7,
                   "frictionless confine500, %s: velocities = newton's (relative)", type));
  PetscCall(PetscFree(va));
  PetscCall(PetscFree(vb));
  PetscCall(KergsStepperDestroy(&a));
  PetscCall(KergsStepperDestroy(&b));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  char type[64] = "vinewtonrsls";

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(PetscOptionsGetString(NULL, NULL, "-test_snes_type", type, sizeof(type), NULL)); /* before MakeStepper clears them */
  PetscCall(TestOneContact(type));
  PetscCall(TestFrictionless(type));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
