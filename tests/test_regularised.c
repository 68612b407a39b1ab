/* The kernel-regularised solvers (NLKerGS-P, NLGS-Jac) at the extremes (issue 3): omega from 1e-6 to 1e3 times
   ||W||_2, eta down to 1e-12, epsilon from 1e-12 to 1, radius ratio 100, mass ratio 1e6, every grain floating,
   huge kernels. Each run must keep every impulse and velocity finite, report its convergence honestly (a step
   that hits the cap says so), and the regularised solvers must agree with each other. */
static const char help[] = "kergs regularised solver tests.\n";

#include "testing.h"
#include "internals.h"

/* Run a scene to the end; report whether everything stayed finite and how many steps claimed convergence
   although their recorded criterion was above the tolerance (must be none). */
static PetscErrorCode RunScene(const char *opts, PetscInt *nonconverged, PetscBool *finite, PetscBool *honest, KergsStepper *keep)
{
  KergsStepper st;
  PetscReal    ek, vmax, conv, crit;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper(opts, &st));
  *finite = PETSC_TRUE;
  *honest = PETSC_TRUE;
  for (PetscInt s = 0; s < st->scene->nsteps; s++) {
    PetscCall(KergsStepperStep(st));
    PetscCall(StatAt(st->results, "converged", s, &conv));
    PetscCall(StatAt(st->results, "criterion", s, &crit));
    if (conv > 0.5 && !(crit < st->solver->tol)) *honest = PETSC_FALSE;
    if (PetscIsInfOrNanReal(crit)) *finite = PETSC_FALSE;
  }
  for (PetscInt k = 0; k < st->contacts->n; k++)
    for (PetscInt c = 0; c < KERGS_MAXCOMP; c++)
      if (PetscIsInfOrNanReal(st->contacts->c[k].r[c])) *finite = PETSC_FALSE;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, finite, 1, MPIU_BOOL, MPI_LAND, PETSC_COMM_WORLD));
  PetscCall(KergsSceneKineticEnergy(st->scene, &ek, &vmax));
  if (PetscIsInfOrNanReal(ek)) *finite = PETSC_FALSE;
  *nonconverged = st->nonconverged;
  if (keep) *keep = st;
  else PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

static PetscErrorCode Extreme(const char *label, const char *opts)
{
  PetscInt  nc;
  PetscBool finite, honest;
  char      what[256];

  PetscFunctionBeginUser;
  PetscCall(RunScene(opts, &nc, &finite, &honest, NULL));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: impulses, velocities, criteria finite", label));
  PetscCall(Check(finite, what, finite, 1));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: a step said converged only below tol", label));
  PetscCall(Check(honest, what, honest, 1));
  PetscFunctionReturn(0);
}

#define CONFINE5 "-options_file cases/confine5.opts -steps 12 "
#define WEDGED   "-options_file cases/two_disks_wedged.opts -steps 10 "

int main(int argc, char **argv)
{
  char         opts[1024];
  const double omegas[] = {1e-6, 1e-3, 1.0 / 20, 1, 1e3};
  const double etas[]   = {1e-12, 1e-6, 1};
  const double epss[]   = {1e-12, 1e-6, 1};
  KergsStepper a, b;
  PetscInt     nca, ncb;
  PetscBool    fa, fb, ha, hb;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  /* omega from 1e-6 to 1e3 times ||W||_2 */
  for (size_t i = 0; i < sizeof(omegas) / sizeof(omegas[0]); i++) {
    PetscCall(PetscSNPrintf(opts, sizeof(opts), CONFINE5 "-solver_type nlgsjac -predictor_type linear -solver_omega_factor %g", omegas[i]));
    PetscCall(Extreme(omegas[i] == 1e-6 ? "omega 1e-6 ||W||" : omegas[i] == 1e3 ? "omega 1e3 ||W||" : "omega in range", opts));
  }
  /* the predictors' factorizations across repartitions (the DOFs of a rank change size: on several ranks) */
  PetscCall(Extreme("nlgsjac, linear predictor, repartitioned every step", CONFINE5 "-solver_type nlgsjac -predictor_type linear -partition_check_every 1 -partition_imbalance_tol 1.0"));
  PetscCall(Extreme("nlgsjac, elastic predictor, repartitioned every step", CONFINE5 "-solver_type nlgsjac -predictor_type elastic -partition_check_every 1 -partition_imbalance_tol 1.0"));
  /* eta down to 1e-12, epsilon from 1e-12 to 1 */
  for (size_t i = 0; i < 3; i++) {
    PetscCall(PetscSNPrintf(opts, sizeof(opts), CONFINE5 "-solver_type nlgsjac -predictor_type linear -predictor_eta %g", etas[i]));
    PetscCall(Extreme("linear predictor, eta 1e-12 .. 1", opts));
    PetscCall(PetscSNPrintf(opts, sizeof(opts), CONFINE5 "-solver_type nlgsjac -predictor_type elastic -predictor_epsilon %g", epss[i]));
    PetscCall(Extreme("elastic predictor, epsilon 1e-12 .. 1", opts));
  }
  PetscCall(Extreme("unilateral predictor", CONFINE5 "-solver_type nlgsjac -predictor_type unilateral"));
  /* huge kernels: the wedged pair, a compressed hexagonal crystal */
  PetscCall(Extreme("wedged pair, nlgsjac", WEDGED "-solver_type nlgsjac -predictor_type linear"));
  PetscCall(Extreme("wedged pair, nlkergs", WEDGED "-solver_type nlkergs -predictor_type linear"));
  PetscCall(Extreme("compressed hexagonal crystal",
                    "-gravity 0,-9.81 -friction 0.3 -dt 1e-3 -steps 5 -disks_source lattice -lattice_type hex -lattice_n 12,8 -lattice_radius 0.05 "
                    "-lattice_origin 0.05,0.05 -box 0,0,1.25,0.7063 -wall_box_top_velocity 0,-0.05 -solver_type nlgsjac -predictor_type linear"));
  /* every grain floating: no contact at all, an empty kernel */
  PetscCall(Extreme("every grain floating", "-gravity 0,0 -dt 1e-3 -steps 3 -disks_source lattice -lattice_n 4,4 -lattice_radius 0.1 -lattice_spacing 0.5 "
                                            "-solver_type nlgsjac -predictor_type linear -friction 0.3"));
  /* radius ratio 100 and mass ratio 1e6 (densities) */
  PetscCall(Extreme("radius ratio 100", "-gravity 0,-9.81 -friction 0.3 -dt 1e-3 -steps 5 -disks_source list -disks_x 1,1,2.01,0.01,0.5,0.01,1.5,0.01 "
                                        "-disks_radius 1,0.01,0.01,0.01 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0 -alert 0.005 "
                                        "-solver_type nlgsjac -predictor_type linear"));
  PetscCall(Extreme("mass ratio 1e6", "-gravity 0,-9.81 -friction 0.3 -dt 1e-3 -steps 5 -materials 2 -material_density 1,1e6 -disks_source list "
                                      "-disks_x 0.1,0.1,0.1,0.3,0.1,0.5 -disks_radius 0.1 -disks_material 0,1,0 -walls floor -wall_floor_a -5,0 "
                                      "-wall_floor_b 5,0 -solver_type nlgsjac -predictor_type linear"));
  /* the infeasible straight row: the regularised solvers report non-convergence too */
  PetscCall(RunScene("-options_file cases/confine5_straight.opts -steps 10 -solver_type nlgsjac -predictor_type linear", &nca, &fa, &ha, NULL));
  PetscCall(Check((PetscBool)(fa && ha), "straight row, nlgsjac: finite and honest", fa && ha, 1));
  /* NLGS-Jac and the stored W~ solve the same regularised problem: same velocities on a frictionless scene */
  PetscCall(RunScene(CONFINE5 "-friction 0 -solver_type nlgsjac -predictor_type unilateral -solver_tol 1e-12 -solver_max_it 5000", &nca, &fa, &ha, &a));
  PetscCall(RunScene(CONFINE5 "-friction 0 -solver_type nlkergs -predictor_type unilateral -solver_tol 1e-12 -solver_max_it 5000", &ncb, &fb, &hb, &b));
  {
    PetscReal dv = 0, vs = 0, *va, *vb;
    PetscCall(PetscMalloc2(2 * a->scene->ndisks, &va, 2 * b->scene->ndisks, &vb));
    PetscCall(GatherById(a->scene, a->scene->v, KERGS_DIM, va));
    PetscCall(GatherById(b->scene, b->scene->v, KERGS_DIM, vb));
    for (PetscInt i = 0; i < 2 * a->scene->ndisks; i++) {
      dv = PetscMax(dv, PetscAbsReal(va[i] - vb[i]));
      vs = PetscMax(vs, PetscAbsReal(va[i]));
    }
    PetscCall(PetscFree2(va, vb));
    PetscCall(Check((PetscBool)(dv <= 1e-6 * vs), "nlgsjac and nlkergs give the same velocities (frictionless)", dv, 0));
  }
  PetscCall(KergsStepperDestroy(&a));
  PetscCall(KergsStepperDestroy(&b));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
