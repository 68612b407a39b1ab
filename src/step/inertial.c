/* kergs stepper: the inertial number of a biaxial-like run, told once at its start. With walls under pressure (the
   confining sigma3) and a driven wall moving along its normal, each such wall shears the sample at
   I = eps_dot d sqrt(rho / sigma3) (GDR MiDi, Eur. Phys. J. E 14 (2004) 341): eps_dot the wall's normal speed
   over its distance to the wall facing it, d the mean grain diameter, rho the grains' density (their mass over their
   area). The quasi-static regime is I below about 1e-3; above 0.1 the response is that of a dense inertial flow, not
   of the sample: a warning, not an error (a fast run may be wanted, for a test of the code).
   I is a grain-scale number. On the sample's scale the wall's speed compares with sqrt(sigma3 / rho), the speed the
   confining pressure gives a grain: v sqrt(rho / sigma3) = I H / d, H the distance to the facing wall. It is 0.07 for
   the 5,000-disk test and 0.13 for the 20,000-disk one at I = 9.5e-4, whose Love-Weber stress matches the walls' to
   2 %. At 10^6 disks (H = 1,000 d) the same I gives 0.93: the sample's inertia, rho v^2 = 0.87 sigma3, is felt, and
   the Love-Weber sxx inside rose to 2.6 sigma3 in 4 steps while the lateral walls held sigma3 (docs/biaxial.md).
   Above 0.3 (rho v^2 above 0.09 sigma3) a second warning says so.
   The same number, measured on the box's walls as they move, is also a rest rule for a compaction under pressure
   (-stop_at_rest_inertial, below): the walls have stopped closing in once I is well below the quasi-static bound. */
#include <kergs/private/stepperimpl.h>

#define KERGS_INERTIAL_WARN 0.1
#define KERGS_SAMPLE_SPEED_WARN 0.3

/* A wall's unit inward normal (the left normal of a -> b) */
static void WallNormal(const KergsWall *w, PetscReal n[])
{
  const PetscReal dx = w->b[0] - w->a[0], dy = w->b[1] - w->a[1], len = PetscSqrtReal(dx * dx + dy * dy);

  n[0] = len > 0 ? -dy / len : 0.0;
  n[1] = len > 0 ? dx / len : 0.0;
}

/* The wall facing wall w (antiparallel normal, in front of it) nearest to it, and its distance; -1 and 0: none */
static PetscInt FacingWall(PetscInt nwalls, const KergsWall walls[], PetscInt w, PetscReal *dist)
{
  PetscReal n[KERGS_DIM];
  PetscInt  facing = -1;

  WallNormal(&walls[w], n);
  *dist = 0;
  for (PetscInt k = 0; k < nwalls; k++) {
    PetscReal m[KERGS_DIM], d;
    WallNormal(&walls[k], m);
    if (k == w || n[0] * m[0] + n[1] * m[1] > -1 + 1e-9) continue;
    d = n[0] * (walls[k].a[0] - walls[w].a[0]) + n[1] * (walls[k].a[1] - walls[w].a[1]);
    if (d > 0 && (facing < 0 || d < *dist)) {
      facing = k;
      *dist  = d;
    }
  }
  return facing;
}

/* The mean diameter and the density (total mass over total area) of every grain. Collective. */
static PetscErrorCode GrainScales(KergsStepper st, PetscReal *d, PetscReal *rho)
{
  KergsDisks D;
  PetscReal  sums[3] = {0, 0, 0}; /* diameters, masses, areas */

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  for (PetscInt i = 0; i < D.nowned; i++) {
    sums[0] += 2 * D.radius[i];
    sums[1] += D.mass[i];
    sums[2] += PETSC_PI * D.radius[i] * D.radius[i];
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPIU_SUM, st->comm));
  *d   = D.ndisks > 0 ? sums[0] / D.ndisks : 0;
  *rho = sums[2] > 0 ? sums[1] / sums[2] : 0;
  PetscFunctionReturn(0);
}

/* A free wall under a positive pressure: what confines the sample, and what -stop_at_rest_inertial judges */
static PetscBool UnderPressure(const KergsWall *wall)
{
  return (PetscBool)(wall->kind == KERGS_WALL_FREE && wall->has_pressure && wall->pressure > 0);
}

/* sigma3: the smallest positive pressure of the pressure-controlled walls (0: none) */
static PetscReal ConfiningPressure(PetscInt nwalls, const KergsWall walls[])
{
  PetscReal sigma3 = 0;

  for (PetscInt w = 0; w < nwalls; w++)
    if (UnderPressure(&walls[w]) && (sigma3 == 0 || walls[w].pressure < sigma3)) sigma3 = walls[w].pressure;
  return sigma3;
}

/* The largest normal speed a driven wall's program reaches from time t on (the piece holding at t and every later
   one): a program that ramps up to a fast final speed is judged by that speed, not by its first piece. */
static PetscReal LargestSpeedAhead(const KergsWall *wall, PetscReal t, const PetscReal n[])
{
  PetscReal speed = 0;

  for (PetscInt k = 0; k < wall->nprog; k++) {
    if (k + 1 < wall->nprog && wall->prog_t[k + 1] <= t) continue; /* over before t */
    speed = PetscMax(speed, PetscAbsReal(n[0] * wall->prog_v[k][0] + n[1] * wall->prog_v[k][1]));
  }
  return speed;
}

/* Before the first step, rank 0 prints one warning per driven wall whose inertial number exceeds 0.1, with the terms
   of the formula, and one per driven wall faster than 0.3 sqrt(sigma3 / rho), each at the largest speed its program
   reaches from the current time on. Silent without a pressure wall or without a driven wall
   moving along its normal. Collective. */
PetscErrorCode KergsStepperWarnInertialNumber(KergsStepper st)
{
  const KergsWall *walls;
  PetscInt         nwalls;
  PetscReal        sigma3, d = 0, rho = 0, time;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetStep(st->scene, NULL, &time, NULL));
  sigma3 = ConfiningPressure(nwalls, walls);
  if (sigma3 == 0) PetscFunctionReturn(0);
  PetscCall(GrainScales(st, &d, &rho));
  for (PetscInt w = 0; w < nwalls; w++) {
    PetscReal n[KERGS_DIM], speed, dist, rate, inertial;
    if (walls[w].kind != KERGS_WALL_DRIVEN) continue;
    WallNormal(&walls[w], n);
    speed = LargestSpeedAhead(&walls[w], time, n);
    (void)FacingWall(nwalls, walls, w, &dist);
    if (!(speed > 0) || !(dist > 0)) continue;
    rate     = speed / dist;
    inertial = rate * d * PetscSqrtReal(rho / sigma3);
    if (speed * PetscSqrtReal(rho / sigma3) > KERGS_SAMPLE_SPEED_WARN)
      PetscCall(PetscPrintf(st->comm,
                            "kergs: warning: wall %s moves at %.3g sqrt(sigma3 / rho) (= I H / d, the sample %.0f mean diameters across), "
                            "above %g: the sample's own inertia rho v^2 = %.2g sigma3 is felt on its scale, whatever I = %.3g; not a "
                            "quasi-static test (docs/biaxial.md, \"The strain rate\")\n",
                            walls[w].name, (double)(speed * PetscSqrtReal(rho / sigma3)), (double)(dist / d),
                            (double)KERGS_SAMPLE_SPEED_WARN, (double)(rho * speed * speed / sigma3), (double)inertial));
    if (!(inertial > KERGS_INERTIAL_WARN)) continue;
    PetscCall(PetscPrintf(st->comm,
                          "kergs: warning: wall %s shears the sample at the inertial number I = eps_dot d sqrt(rho / sigma3) = %.3g, above "
                          "%g (quasi-static: about 1e-3): eps_dot = %g m/s / %g m = %g /s (its normal speed over the distance to the "
                          "wall facing it), d = %g m (mean diameter), rho = %g kg/m^2, sigma3 = %g N/m (the pressure walls); lower "
                          "its speed\n",
                          walls[w].name, (double)inertial, (double)KERGS_INERTIAL_WARN, (double)speed, (double)dist, (double)rate,
                          (double)d, (double)rho, (double)sigma3));
  }
  PetscFunctionReturn(0);
}

/* -stop_at_rest_inertial judges the box by its walls under pressure, each against the wall facing it. Refused before the
   run, each naming what is wrong: a wall under pressure that faces none (its motion would not be judged), a driven wall
   that moves (the box is never at rest: a biaxial test would stop once its lateral walls stopped widening), no wall
   under pressure at all, a window as long as the run (it would never fill), and -stop_at_rest_stress without a box of
   four walls to measure the Love-Weber stress in. Collective. */
PetscErrorCode KergsStepperCheckRestInertial(KergsStepper st)
{
  const KergsWall *walls;
  PetscInt         nwalls, judged = 0, step, nsteps;
  PetscReal        time, dist, n[KERGS_DIM];
  PetscBool        box;

  PetscFunctionBeginUser;
  if (!(st->rest_inertial > 0)) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetStep(st->scene, &step, &time, &nsteps));
  for (PetscInt w = 0; w < nwalls; w++) {
    WallNormal(&walls[w], n);
    PetscCheck(walls[w].kind != KERGS_WALL_DRIVEN || LargestSpeedAhead(&walls[w], time, n) == 0, st->comm, PETSC_ERR_ARG_INCOMP,
               "-stop_at_rest_inertial judges a box closed by walls under pressure, and wall %s is driven at a speed along its normal: "
               "the box is never at rest; stop by -steps",
               walls[w].name);
    if (!UnderPressure(&walls[w])) continue;
    PetscCheck(FacingWall(nwalls, walls, w, &dist) >= 0, st->comm, PETSC_ERR_ARG_INCOMP,
               "-stop_at_rest_inertial measures the box's strain rate between facing walls, and wall %s, under pressure, faces none",
               walls[w].name);
    judged++;
  }
  PetscCheck(judged > 0, st->comm, PETSC_ERR_ARG_INCOMP,
             "-stop_at_rest_inertial %g measures the box's strain rate by its walls under pressure, and no free wall is under a pressure: "
             "give a wall -wall_<name>_type free and -wall_<name>_pressure, or stop by -stop_at_rest or -stop_at_rest_energy",
             (double)st->rest_inertial);
  PetscCall(KergsStepperHasBox(st, &box));
  PetscCheck(box || !(st->rest_stress > 0), st->comm, PETSC_ERR_ARG_INCOMP,
             "-stop_at_rest_stress %g compares the Love-Weber stress over the box's area with the stress of the walls' tractions, and the "
             "%" PetscInt_FMT " walls are not a box of four axis-aligned walls: give -stop_at_rest_stress 0",
             (double)st->rest_stress, nwalls);
  PetscCheck(st->rest_window < nsteps - step, st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-stop_at_rest_window %" PetscInt_FMT " is not shorter than the %" PetscInt_FMT " steps left to run (-steps %" PetscInt_FMT
             "): the window would never fill",
             st->rest_window, nsteps - step, nsteps);
  PetscFunctionReturn(0);
}

/* A slot of the ring: the step's time, the Love-Weber minus the boundary's sxx, syy, sxy after it, then each wall's
   position along its own normal */
#define BOX_HEAD 4

/* The step's time, its stress out of equilibrium and the walls into the next slot of the ring of -stop_at_rest_window + 1
   slots. Collective only the first time (the grains' scales). */
static PetscErrorCode PushBox(KergsStepper st)
{
  const KergsWall *walls;
  PetscInt         nwalls, slots = st->rest_window + 1;
  PetscReal        time, n[KERGS_DIM], *cur;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetStep(st->scene, NULL, &time, NULL));
  if (!st->box_track) PetscCall(PetscMalloc1(slots * (BOX_HEAD + nwalls), &st->box_track));
  if (st->grain_d == 0) PetscCall(GrainScales(st, &st->grain_d, &st->grain_rho));
  cur    = st->box_track + (st->box_tracked % slots) * (BOX_HEAD + nwalls);
  cur[0] = time;
  for (PetscInt i = 0; i < 3; i++) cur[1 + i] = st->inertia_stress[i]; /* before the first step: unused */
  for (PetscInt w = 0; w < nwalls; w++) {
    WallNormal(&walls[w], n);
    cur[BOX_HEAD + w] = n[0] * walls[w].a[0] + n[1] * walls[w].a[1];
  }
  st->box_tracked++;
  PetscFunctionReturn(0);
}

/* Before the first step of this run: the walls where they start, the ring's first slot */
PetscErrorCode KergsStepperStartBox(KergsStepper st)
{
  PetscFunctionBeginUser;
  if (st->rest_inertial > 0 && st->box_tracked == 0) PetscCall(PushBox(st));
  PetscFunctionReturn(0);
}

/* The slot j steps after the window's start (0: the oldest slot, the walls before the window's first step) */
static const PetscReal *BoxSlot(KergsStepper st, PetscInt stride, PetscInt j)
{
  return st->box_track + ((st->box_tracked + j) % (st->rest_window + 1)) * stride;
}

/* How far the sample is from quasi-static equilibrium with its walls: the largest over the walls under pressure of
   |n.(sigma_LW - sigma_B).n| / p, sigma_LW the Love-Weber stress and sigma_B the boundary's (every wall traction's
   moment, friction included), both averaged over the window's steps, n the wall's normal (-1 without a box). Their
   difference is the stress of the grains' inertia, sum m dv/dt (x) x over the box's area (src/step/macro.c): 0 at
   rest whatever the walls' friction, which sets both apart from the walls' pressure (by 6 % at rest in the 120-grain
   compaction of tests/check_biaxial.py at mu = 0.5, walls included). Averaged because a step's stress is noisy at
   rest: 20,000 disks under NLGS to quad 1e-4 swing by up to 17 % of p from one step to the next while the window's
   mean is within 1 to 3 % (docs/biaxial.md). */
static PetscReal StressGap(KergsStepper st, PetscInt nwalls, const KergsWall walls[], PetscInt stride)
{
  PetscReal mean[3] = {0, 0, 0}, gap = -1, n[KERGS_DIM];

  if (!st->inertia_found) return -1;
  for (PetscInt j = 1; j <= st->rest_window; j++)
    for (PetscInt i = 0; i < 3; i++) mean[i] += BoxSlot(st, stride, j)[1 + i] / st->rest_window;
  for (PetscInt w = 0; w < nwalls; w++) {
    if (!UnderPressure(&walls[w])) continue;
    WallNormal(&walls[w], n);
    gap = PetscMax(gap, PetscAbsReal(mean[0] * n[0] * n[0] + 2 * mean[2] * n[0] * n[1] + mean[1] * n[1] * n[1]) / walls[w].pressure);
  }
  return gap;
}

/* After each step the walls and the stress go into the ring. Once it holds a whole window, the box's inertial number
   is the largest over the walls under pressure of I = eps_dot d sqrt(rho / p), p the wall's pressure and eps_dot the
   path its distance to the wall facing it has travelled over the window (the sum of the steps' changes, in absolute
   value), over the window's duration and over that distance now: the mean strain rate of the box along that wall's
   normal, both walls' motions included. A path over a window rather than the walls' velocities: a free wall rebounds,
   and its velocity changes sign while the box still closes in. Recorded as inertial_number (-1 until the window is
   full), and beside it how far the window's Love-Weber stress is from the walls' as stress_gap (StressGap; -1 as long
   as inertial_number is). */
PetscErrorCode KergsStepperTrackBox(KergsStepper st)
{
  const KergsWall *walls;
  PetscInt         nwalls, stride;
  PetscReal        largest = -1, gap = -1;

  PetscFunctionBeginUser;
  PetscCall(PushBox(st));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  stride = BOX_HEAD + nwalls;
  if (st->box_tracked >= st->rest_window + 1) {
    const PetscReal *newest = BoxSlot(st, stride, st->rest_window), *oldest = BoxSlot(st, stride, 0);
    for (PetscInt w = 0; w < nwalls; w++) {
      PetscReal dist, path = 0;
      PetscInt  k = FacingWall(nwalls, walls, w, &dist);
      if (!UnderPressure(&walls[w]) || k < 0 || !(newest[0] > oldest[0])) continue;
      for (PetscInt j = 1; j <= st->rest_window; j++) { /* the window's steps, oldest first: the distance is -(pos_w + pos_k) */
        const PetscReal *a = BoxSlot(st, stride, j - 1), *b = BoxSlot(st, stride, j);
        path += PetscAbsReal((b[BOX_HEAD + w] + b[BOX_HEAD + k]) - (a[BOX_HEAD + w] + a[BOX_HEAD + k]));
      }
      largest = PetscMax(largest, path / ((newest[0] - oldest[0]) * dist) * st->grain_d * PetscSqrtReal(st->grain_rho / walls[w].pressure));
    }
    gap = StressGap(st, nwalls, walls, stride);
  }
  st->box_inertial   = largest;
  st->box_stress_gap = gap;
  if (st->box_inertial >= st->rest_inertial) st->inertial_armed = PETSC_TRUE;
  PetscCall(KergsResultsRecord(st->results, "inertial_number", st->box_inertial));
  PetscCall(KergsResultsRecord(st->results, "stress_gap", st->box_stress_gap));
  PetscFunctionReturn(0);
}
