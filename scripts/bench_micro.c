/* kergs micro-benchmarks, one JSON line each on stdout (run by scripts/bench, built with the tests: tests/bench.cmake).
   They were timing-only sections of the test programs: a measured value is not a pass/fail property, so
   they live here, each with the accuracy the measured computation reached, so that a fast but wrong run shows.
     sweep   the NLGS sweep on the hand-built lattice of tests/lattice.h (frictional, W = H^T M^-1 H + 0.05 I):
             ns per local contact per sweep, with the quad criterion and the natural residual after the sweeps
     kernel  the kernel projector on a compressed hexagonal crystal (2,000 disks by default): set-up and factor,
             one application, diagonal blocks exact and bound, with |H_f P x| / |x| and |P P x - P x| / |x|
     detect  contact detection on a jittered lattice of 50,000 disks stored in random order: ns per grain of a first
             and a second (persistent) detection on the slowest rank, with the number of contacts found
   Options: -only sweep|kernel|detect, -sweep_contacts <n> (50000), -sweep_count <n> (20), -kernel_lattice <nx,ny>
   (50,40), -detect_lattice <nx,ny> (250,200). Runs on any number of ranks. */
#include "testing.h"
#include "lattice.h"

static const char help[] = "kergs micro-benchmarks (JSON lines).\n";

static PetscErrorCode BenchSweep(MPI_Comm comm)
{
  const PetscInt     ncomp  = 2;
  PetscInt           target = 50000, nsweep = 20, g, nnz;
  KergsSweep         sweep;
  KergsSweepMeasures m;
  Lattice            L;
  Mat                W;
  Vec                vd, r, v;
  PetscReal         *mus, res;
  PetscBool         *active;
  PetscLogDouble     t0, t1, tloc, tmax;
  MatInfo            info;
  PetscMPIInt        size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-sweep_contacts", &target, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-sweep_count", &nsweep, NULL));
  g = (PetscInt)PetscCeilReal(PetscSqrtReal(target / 3.0)) + 1;
  PetscCall(LatticeCreate(g, g, &L));
  PetscCall(LatticeProblem(comm, &L, ncomp, 0.3, 0.05, &W, &vd, &mus, &active));
  PetscCall(MatGetInfo(W, MAT_GLOBAL_SUM, &info));
  nnz = (PetscInt)info.nz_used;
  PetscCall(MatCreateVecs(W, &r, &v));
  PetscCall(KergsSweepCreate(comm, &sweep));
  PetscCall(KergsSweepSetUp(sweep, W, ncomp, mus, active));
  PetscCall(VecSet(r, 0.0));
  PetscCall(KergsSweepRun(sweep, r, vd, NULL, NULL, &m)); /* warm up */
  PetscCallMPI(MPI_Barrier(comm));
  PetscCall(PetscTime(&t0));
  for (PetscInt k = 0; k < nsweep; k++) PetscCall(KergsSweepRun(sweep, r, vd, NULL, NULL, &m));
  PetscCall(PetscTime(&t1));
  tloc = (t1 - t0) / (nsweep * (PetscReal)PetscMax(sweep->n, 1));
  PetscCallMPI(MPI_Allreduce(&tloc, &tmax, 1, MPI_DOUBLE, MPI_MAX, comm));
  PetscCall(KergsSweepNaturalResidual(sweep, r, vd, v, &res));
  PetscCall(PetscPrintf(comm,
                        "{\"bench\": \"sweep_lattice\", \"ranks\": %d, \"contacts\": %" PetscInt_FMT
                        ", \"nonzeros_per_row\": %.2f, \"sweeps\": %" PetscInt_FMT
                        ", \"ns_per_contact_sweep\": %.2f, \"quad\": %.3e, \"natural_residual\": %.3e}\n",
                        size, L.ncontact, (double)nnz / (ncomp * L.ncontact), nsweep + 1, 1e9 * tmax, (double)m.quad, (double)res));
  PetscCall(KergsSweepDestroy(&sweep));
  PetscCall(PetscFree2(mus, active));
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&v));
  PetscCall(VecDestroy(&vd));
  PetscCall(MatDestroy(&W));
  PetscCall(LatticeDestroy(&L));
  PetscFunctionReturn(0);
}

static PetscErrorCode BenchKernel(MPI_Comm comm)
{
  KergsStepper     st;
  KergsKernel      k;
  KergsKernelStats ks;
  Vec              x, y, Px, PPx, HPx;
  PetscLogDouble   t0, t1;
  PetscReal        tex, tbd, nx, nHPx, dPP, w;
  PetscInt         n[2] = {50, 40}, two = 2;
  const PetscInt   napply = 20;
  PetscRandom      rnd;
  PetscMPIInt      size;
  char             opts[1024];

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscOptionsGetIntArray(NULL, NULL, "-kernel_lattice", n, &two, NULL));
  /* the lattice fills its box: the top and right walls are one radius beyond the last disks */
  w = 0.005;
  PetscCall(PetscSNPrintf(
      opts, sizeof(opts),
      "-gravity 0,-9.81 -friction 0.3 -dt 1e-4 -disks_source lattice -lattice_type hex -lattice_n %" PetscInt_FMT ",%" PetscInt_FMT
      " -lattice_radius %g -lattice_origin %g,%g -box 0,0,%.10g,%.10g -wall_box_top_velocity 0,-0.05 -wall_box_right_velocity -0.05,0 "
      "-alert 5e-4 -solver_max_it 20",
      n[0], n[1], w, w, w, (2 * n[0] + 1) * w, PetscFloorReal(1e7 * w * (2 + PetscSqrtReal(3.0) * (n[1] - 1))) / 1e7));
  PetscCall(MakeStepperOn(comm, opts, &st));
  PetscCall(KergsStepperStep(st));
  PetscCall(KergsContactsDetect(st->contacts, st->scene));
  PetscCall(KergsOperatorsAssemble(st->ops, st->scene, st->contacts));
  PetscCall(KergsKernelCreate(comm, &k));
  PetscCall(KergsKernelSetFromOptions(k));
  PetscCall(KergsKernelSetUp(k, st->scene, st->contacts, st->ops));
  PetscCall(KergsKernelSetOmega(k, 1.0));
  PetscCall(VecDuplicate(st->ops->r, &x));
  PetscCall(VecDuplicate(st->ops->r, &y));
  PetscCall(VecDuplicate(st->ops->r, &Px));
  PetscCall(VecDuplicate(st->ops->r, &PPx));
  PetscCall(VecDuplicate(st->ops->Vf, &HPx));
  PetscCall(VecSet(x, 1.0));
  PetscCall(PetscTime(&t0));
  for (PetscInt i = 0; i < napply; i++) PetscCall(KergsKernelProject(k, x, y));
  PetscCall(PetscTime(&t1));
  k->diagtype = KERGS_KERNEL_DIAG_EXACT;
  PetscCall(KergsKernelComputeDiagonalBlocks(k));
  tex         = k->diag_seconds;
  k->diagtype = KERGS_KERNEL_DIAG_BOUND;
  PetscCall(KergsKernelComputeDiagonalBlocks(k));
  tbd = k->diag_seconds;
  /* accuracy: P x in ker H_f, P idempotent */
  PetscCall(PetscRandomCreate(comm, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1, 1));
  PetscCall(VecSetRandom(x, rnd));
  PetscCall(KergsKernelProject(k, x, Px));
  PetscCall(KergsKernelProject(k, Px, PPx));
  PetscCall(MatMultTranspose(st->ops->HfT, Px, HPx));
  PetscCall(VecNorm(x, NORM_2, &nx));
  PetscCall(VecNorm(HPx, NORM_2, &nHPx));
  PetscCall(VecAXPY(PPx, -1.0, Px));
  PetscCall(VecNorm(PPx, NORM_2, &dPP));
  if (nx == 0) nx = 1;
  PetscCall(KergsKernelGetStats(k, &ks));
  PetscCall(PetscPrintf(comm,
                        "{\"bench\": \"kernel_hex\", \"ranks\": %d, \"disks\": %" PetscInt_FMT ", \"rows\": %" PetscInt_FMT
                        ", \"cols\": %" PetscInt_FMT ", \"rank_Hf\": %" PetscInt_FMT
                        ", \"package\": \"%s\", \"factor_seconds\": %.4g, \"apply_ms\": %.4g, \"diag_exact_seconds\": %.4g, "
                        "\"diag_bound_seconds\": %.4g, \"HfPx_over_x\": %.3e, \"PPx_minus_Px_over_x\": %.3e}\n",
                        size, st->scene->ndisks, ks.nrows, ks.ncols, ks.rank, ks.package ? ks.package : "", (double)ks.factor_seconds,
                        1e3 * (double)(t1 - t0) / napply, (double)tex, (double)tbd, (double)(nHPx / nx), (double)(dPP / nx)));
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(VecDestroy(&Px));
  PetscCall(VecDestroy(&PPx));
  PetscCall(VecDestroy(&HPx));
  PetscCall(KergsKernelDestroy(&k));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* splitmix64, identical on every rank */
static PetscReal Uniform(unsigned long long *state)
{
  unsigned long long z = (*state += 0x9E3779B97F4A7C15ULL);

  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z = z ^ (z >> 31);
  return (PetscReal)(z >> 11) * (1.0 / 9007199254740992.0);
}

static void SetWall(KergsScene s, PetscInt w, PetscReal ax, PetscReal ay, PetscReal bx, PetscReal by)
{
  KergsWall *wall = &s->walls[w];

  (void)PetscSNPrintf(wall->name, sizeof(wall->name), "wall%d", (int)w);
  wall->infinite = PETSC_TRUE;
  wall->a[0]     = ax;
  wall->a[1]     = ay;
  wall->b[0]     = bx;
  wall->b[1]     = by;
}

static PetscErrorCode BenchDetect(MPI_Comm comm)
{
  PetscInt           n[2] = {250, 200}, two = 2, ndisks, *perm, *material, nglobal[2];
  KergsScene         s;
  KergsContacts      ct;
  PetscReal         *x, *r;
  unsigned long long seed = 7;
  PetscLogDouble     t0, t1, t2, tmax[2], tloc[2];
  PetscMPIInt        size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscOptionsGetIntArray(NULL, NULL, "-detect_lattice", n, &two, NULL));
  ndisks = n[0] * n[1];
  PetscCall(KergsSceneCreate(comm, &s));
  PetscCall(PetscStrcpy(s->name, "bench_detect"));
  s->alert  = 0.05;
  s->nwalls = 4;
  PetscCall(PetscCalloc1(4, &s->walls));
  /* jittered triangular lattice of spacing 2 (six neighbours each), radii 0.97 .. 1.03, stored in a random
     permutation (the worst case for memory access); gaps spread over [-0.16, 0.16] around the alert distance */
  PetscCall(PetscMalloc4(ndisks, &perm, 2 * ndisks, &x, ndisks, &r, ndisks, &material));
  for (PetscInt i = 0; i < ndisks; i++) perm[i] = i;
  for (PetscInt i = ndisks - 1; i > 0; i--) {
    PetscInt j = (PetscInt)(Uniform(&seed) * (PetscReal)(i + 1)), tmp = perm[i];
    perm[i] = perm[j];
    perm[j] = tmp;
  }
  for (PetscInt i = 0; i < ndisks; i++) {
    const PetscInt k = perm[i], row = i / n[0], col = i % n[0];
    x[2 * k]     = 2.0 * (PetscReal)col + (PetscReal)(row % 2) + 1.0 + 0.1 * (Uniform(&seed) - 0.5);
    x[2 * k + 1] = PetscSqrtReal(3.0) * (PetscReal)row + 1.0 + 0.1 * (Uniform(&seed) - 0.5);
    r[k]         = 0.97 + 0.06 * Uniform(&seed);
    material[k]  = 0;
  }
  PetscCall(KergsSceneSetDisks(s, ndisks, x, r, material, NULL));
  for (PetscInt i = 0; i < s->nowned; i++) s->id[i] = 1000 + s->dstart + i;
  SetWall(s, 0, 0, 0, 1, 0);
  SetWall(s, 1, 0, 1, 0, 0);
  SetWall(s, 2, 2.0 * n[0] + 1.0, 0, 2.0 * n[0] + 1.0, 1);
  SetWall(s, 3, 1, PetscSqrtReal(3.0) * n[1], 0, PetscSqrtReal(3.0) * n[1]);
  PetscCall(KergsContactsCreate(comm, &ct));
  PetscCallMPI(MPI_Barrier(comm));
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(PetscTime(&t1));
  nglobal[0] = ct->nglobal;
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(PetscTime(&t2));
  nglobal[1] = ct->nglobal;
  tloc[0]    = t1 - t0;
  tloc[1]    = t2 - t1;
  PetscCallMPI(MPI_Allreduce(tloc, tmax, 2, MPI_DOUBLE, MPI_MAX, comm));
  PetscCall(PetscPrintf(comm,
                        "{\"bench\": \"detect_lattice\", \"ranks\": %d, \"disks\": %" PetscInt_FMT ", \"contacts\": %" PetscInt_FMT
                        ", \"contacts_second\": %" PetscInt_FMT ", \"first_ns_per_grain\": %.1f, \"second_ns_per_grain\": %.1f}\n",
                        size, ndisks, nglobal[0], nglobal[1], 1e9 * tmax[0] / ndisks, 1e9 * tmax[1] / ndisks));
  PetscCall(PetscFree4(perm, x, r, material));
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  char      only[32] = "";
  PetscBool all;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(PetscOptionsGetString(NULL, NULL, "-only", only, sizeof(only), NULL));
  all = (PetscBool)!only[0];
  /* the kernel benchmark's stepper clears the options database: read every option first */
  if (all || !strcmp(only, "sweep")) PetscCall(BenchSweep(PETSC_COMM_WORLD));
  if (all || !strcmp(only, "detect")) PetscCall(BenchDetect(PETSC_COMM_WORLD));
  if (all || !strcmp(only, "kernel")) PetscCall(BenchKernel(PETSC_COMM_WORLD));
  PetscCall(PetscFinalize());
  return 0;
}
