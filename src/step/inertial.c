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
   Above 0.3 (rho v^2 above 0.09 sigma3) a second warning says so. */
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

/* The distance from wall w to the nearest wall facing it (antiparallel normal, in front of it); 0: none. */
static PetscReal FacingDistance(PetscInt nwalls, const KergsWall walls[], PetscInt w)
{
  PetscReal n[KERGS_DIM], best = 0;

  WallNormal(&walls[w], n);
  for (PetscInt k = 0; k < nwalls; k++) {
    PetscReal m[KERGS_DIM], dist;
    WallNormal(&walls[k], m);
    if (k == w || n[0] * m[0] + n[1] * m[1] > -1 + 1e-9) continue;
    dist = n[0] * (walls[k].a[0] - walls[w].a[0]) + n[1] * (walls[k].a[1] - walls[w].a[1]);
    if (dist > 0 && (best == 0 || dist < best)) best = dist;
  }
  return best;
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

/* sigma3: the smallest positive pressure of the pressure-controlled walls (0: none) */
static PetscReal ConfiningPressure(PetscInt nwalls, const KergsWall walls[])
{
  PetscReal sigma3 = 0;

  for (PetscInt w = 0; w < nwalls; w++)
    if (walls[w].kind == KERGS_WALL_FREE && walls[w].has_pressure && walls[w].pressure > 0 && (sigma3 == 0 || walls[w].pressure < sigma3))
      sigma3 = walls[w].pressure;
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
    dist  = FacingDistance(nwalls, walls, w);
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

/* Whether wall w is under a pressure and faces another wall: the walls whose motion -stop_at_rest_inertial judges */
static PetscBool PressureWallFacing(PetscInt nwalls, const KergsWall walls[], PetscInt w)
{
  return (PetscBool)(walls[w].kind == KERGS_WALL_FREE && walls[w].has_pressure && walls[w].pressure > 0 &&
                     FacingDistance(nwalls, walls, w) > 0);
}

/* -stop_at_rest_inertial judges the walls under pressure: a scene without one facing another wall is refused before the
   run, rather than never at rest. Collective. */
PetscErrorCode KergsStepperCheckRestInertial(KergsStepper st)
{
  const KergsWall *walls;
  PetscInt         nwalls, judged = 0;

  PetscFunctionBeginUser;
  if (!(st->rest_inertial > 0)) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  for (PetscInt w = 0; w < nwalls; w++) judged += PressureWallFacing(nwalls, walls, w);
  PetscCheck(judged > 0, st->comm, PETSC_ERR_ARG_INCOMP,
             "-stop_at_rest_inertial %g measures the box's strain rate by its walls under pressure, and no wall has one facing another "
             "wall: give a wall -wall_<name>_type free and -wall_<name>_pressure, or stop by -stop_at_rest or -stop_at_rest_energy",
             (double)st->rest_inertial);
  PetscFunctionReturn(0);
}

/* After each step: the step's time and each wall's position along its normal go into a ring of -stop_at_rest_window + 1
   slots. Once it is full, the box's inertial number over the window is the largest over the walls under pressure of
   I = eps_dot d sqrt(rho / p), eps_dot = |displacement along the normal| / (window's duration * distance to the wall
   facing it), p the wall's pressure: a window rather than the walls' velocities because a free wall's velocity
   changes sign as it rebounds (at 300 disks the window of 50 steps measured 1.3e-4 where the velocity gave 2.4e-5).
   Recorded as inertial_number in the current row (-1 until the window is full). Collective. */
PetscErrorCode KergsStepperTrackBox(KergsStepper st)
{
  const KergsWall *walls;
  PetscInt         nwalls, slots = st->rest_window + 1, now, then;
  PetscReal        time, n[KERGS_DIM], *cur, *old, largest = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetStep(st->scene, NULL, &time, NULL));
  if (!st->box_track) PetscCall(PetscMalloc1(slots * (1 + nwalls), &st->box_track));
  if (st->grain_d == 0) PetscCall(GrainScales(st, &st->grain_d, &st->grain_rho));
  now    = st->box_tracked % slots;
  cur    = st->box_track + now * (1 + nwalls);
  cur[0] = time;
  for (PetscInt w = 0; w < nwalls; w++) {
    WallNormal(&walls[w], n);
    cur[1 + w] = n[0] * walls[w].a[0] + n[1] * walls[w].a[1];
  }
  st->box_tracked++;
  st->box_inertial = -1;
  if (st->box_tracked >= slots) {
    then = st->box_tracked % slots; /* the oldest slot, window steps ago */
    old  = st->box_track + then * (1 + nwalls);
    for (PetscInt w = 0; w < nwalls; w++) {
      PetscReal rate;
      if (!PressureWallFacing(nwalls, walls, w) || !(cur[0] > old[0])) continue;
      rate    = PetscAbsReal(cur[1 + w] - old[1 + w]) / ((cur[0] - old[0]) * FacingDistance(nwalls, walls, w));
      largest = PetscMax(largest, rate * st->grain_d * PetscSqrtReal(st->grain_rho / walls[w].pressure));
    }
    st->box_inertial = largest;
  }
  PetscCall(KergsResultsRecord(st->results, "inertial_number", st->box_inertial));
  PetscFunctionReturn(0);
}
