/* Tests of the scene: options, generators (list, lattice, random), walls and their programs, ownership,
   kinetic energy, and the errors of bad input. Run on 1 and 2 ranks: the disk state is distributed (each rank
   owns a contiguous slice), so the checks gather the disks in global-index order (KergsSceneAllGather*), and
   the gathered scene must be exactly the same on every rank and on any number of ranks.
   With -from_command_line the program instead builds a scene from the command line and views it (for -help). */
#include "testing.h"
#include "gathered_disks.h"
#include <petscviewer.h>

static PetscBool Close(PetscReal a, PetscReal b, PetscReal tol)
{
  return PetscAbsReal(a - b) <= tol * PetscMax(1.0, PetscMax(PetscAbsReal(a), PetscAbsReal(b))) ? PETSC_TRUE : PETSC_FALSE;
}

/* Build a scene from an options string in a private options database; *ierr is the error of SetFromOptions
   (0 on success), *msg its message. The scene is returned even after an error (destroy it). */
static PetscErrorCode SceneFromString(MPI_Comm comm, const char opts[], KergsScene *scene, PetscErrorCode *ierr, const char **msg)
{
  PetscOptions options;
  char        *specific = NULL;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsCreate(&options));
  PetscCall(PetscOptionsInsertString(options, opts));
  PetscCall(PetscOptionsPush(options));
  PetscCall(KergsSceneCreate(comm, scene));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  *ierr = KergsSceneSetFromOptions(*scene);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscOptionsPop());
  PetscCall(PetscOptionsDestroy(&options));
  if (msg) {
    *msg = "";
    if (*ierr) {
      PetscCall(PetscErrorMessage(*ierr, NULL, &specific));
      if (specific) *msg = specific;
    }
  }
  PetscFunctionReturn(0);
}

/* Build a scene that must be valid: checked; on failure *scene is NULL and the caller returns (nothing to look at). */
static PetscErrorCode SceneGood(MPI_Comm comm, const char opts[], KergsScene *scene)
{
  PetscErrorCode ierr;
  const char    *msg;
  char           what[2048];

  PetscFunctionBeginUser;
  PetscCall(SceneFromString(comm, opts, scene, &ierr, &msg));
  if (ierr) {
    PetscCall(PetscSNPrintf(what, sizeof(what), "valid options \"%s\" accepted [%s]", opts, msg));
    PetscCall(CheckTrue(comm, PETSC_FALSE, what));
    PetscCall(KergsSceneDestroy(scene));
  }
  PetscFunctionReturn(0);
}

/* Smallest centre distance over all pairs, the number of pairs at distance d (relative tolerance tol), and
   whether any pair overlaps (distance < (r_i + r_j)(1 - tol): touching lattice disks differ from 2r by
   rounding). Brute force over the gathered disks. */
static PetscErrorCode PairStats(const Disks *s, PetscReal d, PetscReal tol, PetscReal *dmin, PetscInt *nat, PetscBool *overlap)
{
  PetscFunctionBeginUser;
  *dmin    = PETSC_MAX_REAL;
  *nat     = 0;
  *overlap = PETSC_FALSE;
  for (PetscInt i = 0; i < s->n; i++) {
    for (PetscInt j = i + 1; j < s->n; j++) {
      const PetscReal dx = s->x[2 * j] - s->x[2 * i], dy = s->x[2 * j + 1] - s->x[2 * i + 1], dist = PetscSqrtReal(dx * dx + dy * dy);

      *dmin = PetscMin(*dmin, dist);
      if (PetscAbsReal(dist - d) <= tol * d) (*nat)++;
      if (dist < (s->radius[i] + s->radius[j]) * (1.0 - tol)) *overlap = PETSC_TRUE;
    }
  }
  PetscFunctionReturn(0);
}

/* The ownership ranges of all ranks are contiguous, cover [0, ndisks) and differ in size by at most one; each
   rank's local arrays start with its owned disks, global indices dstart, dstart + 1, ... */
static PetscErrorCode CheckOwnership(KergsScene s)
{
  PetscMPIInt size;
  PetscInt    range[2] = {s->dstart, s->dend}, *all, nmin = PETSC_MAX_INT, nmax = 0;
  PetscBool   ok, layout = (PetscBool)(s->nowned == s->dend - s->dstart && s->nlocal >= s->nowned);

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(PetscMalloc1(2 * size, &all));
  PetscCallMPI(MPI_Allgather(range, 2, MPIU_INT, all, 2, MPIU_INT, s->comm));
  ok = (all[0] == 0 && all[2 * size - 1] == s->ndisks) ? PETSC_TRUE : PETSC_FALSE;
  for (PetscMPIInt p = 0; p < size; p++) {
    if (p > 0 && all[2 * p] != all[2 * p - 1]) ok = PETSC_FALSE;
    nmin = PetscMin(nmin, all[2 * p + 1] - all[2 * p]);
    nmax = PetscMax(nmax, all[2 * p + 1] - all[2 * p]);
  }
  if (nmax - nmin > 1) ok = PETSC_FALSE;
  for (PetscInt i = 0; layout && i < s->nowned; i++)
    if (s->gidx[i] != s->dstart + i) layout = PETSC_FALSE;
  PetscCall(CheckTrue(s->comm, ok, "ownership ranges are contiguous, cover every disk and are balanced"));
  PetscCall(CheckTrue(s->comm, layout, "owned disks first in the local arrays, in global-index order (gidx = dstart + i)"));
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestList(MPI_Comm comm)
{
  KergsScene      s;
  Disks           all;
  const PetscReal m0 = 2.0 * PETSC_PI * 0.25, m1 = 3.0 * PETSC_PI * 0.04; /* density * pi r^2 */
  PetscReal       mu01, mu10, mu00;

  PetscFunctionBeginUser;
  PetscCall(SceneGood(
      comm,
      "-scene_name listed -materials 2 -material_density 2,3 -friction_pairs 0,1,0.4 -disks_x 0,0,1,0,0.5,0.8 -disks_radius 0.5,0.2,0.5 "
      "-disks_material 0,1,0 -disks_velocity 1,2,0,0,0,-1 -dt 0.01 -steps 10 -theta 0.5 -gap_rule lmgc90 -gravity 0,-1",
      &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)(s->ndisks == 3 && s->nwalls == 0), "list: 3 disks, no walls"));
  PetscCall(DisksGather(s, &all));
  PetscCall(CheckTrue(comm,
                      (PetscBool)(all.x[2] == 1.0 && all.x[5] == 0.8 && all.radius[1] == 0.2 && all.material[1] == 1 && all.v[1] == 2.0 &&
                                  all.v[5] == -1.0),
                      "list: positions, radii, materials and velocities as given"));
  PetscCall(CheckTrue(
      comm, (PetscBool)(Close(all.mass[0], m0, 1e-14) && Close(all.mass[1], m1, 1e-14) && Close(all.inertia[1], 0.5 * m1 * 0.04, 1e-14)),
      "list: mass = density pi r^2, inertia = m r^2 / 2"));
  PetscCall(CheckTrue(comm, (PetscBool)(all.id[0] == 0 && all.id[1] == 1 && all.id[2] == 2 && all.rot[2] == 0.0 && all.omega[2] == 0.0),
                      "list: id = index, rot = omega = 0"));
  PetscCall(DisksFree(&all));
  PetscCall(KergsSceneFriction(s, 0, 1, &mu01));
  PetscCall(KergsSceneFriction(s, 1, 0, &mu10));
  PetscCall(KergsSceneFriction(s, 0, 0, &mu00));
  PetscCall(CheckTrue(comm, (PetscBool)(mu01 == 0.4 && mu10 == 0.4 && mu00 == 0.0),
                      "list: -friction_pairs sets mu symmetrically, others keep -friction (0)"));
  PetscCall(CheckTrue(comm, s->frictional, "list: frictional, since materials 0 and 1 both have disks"));
  PetscCall(CheckTrue(
      comm, (PetscBool)(s->dt == 0.01 && s->nsteps == 10 && s->theta == 0.5 && s->gaprule == KERGS_GAP_LMGC90 && s->gravity[1] == -1.0),
      "list: dt, steps, theta, gap rule, gravity as given"));
  PetscCall(CheckTrue(comm, Close(s->alert, 0.1 * 1.2 / 3.0, 1e-14), "list: default alert = 0.1 * mean radius"));
  PetscCall(CheckOwnership(s));
  PetscCall(KergsSceneView(s, PETSC_VIEWER_STDOUT_(comm)));
  PetscCall(KergsSceneDestroy(&s));

  /* the friction of a pair that cannot meet does not make the scene frictional */
  PetscCall(SceneGood(comm, "-materials 2 -friction_pairs 0,1,0.4 -disks_x 0,0,1,0 -disks_radius 0.5 -alert 0.02", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)!s->frictional, "frictional = FALSE when only material 0 is present"));
  PetscCall(CheckTrue(comm, (PetscBool)(s->alert == 0.02), "-alert overrides the default"));
  PetscCall(KergsSceneDestroy(&s));
  /* the word default brings back the automatic alert over an options file's value */
  PetscCall(SceneGood(comm, "-disks_x 0,0,1,0 -disks_radius 0.5 -alert default", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)(Close(s->alert, 0.05, 1e-14) && s->alert_auto), "-alert default: automatic, 0.1 * mean radius"));
  PetscCall(KergsSceneDestroy(&s));
  PetscCall(SceneGood(
      comm, "-materials 2 -friction_pairs 0,1,0.4 -disks_x 0,0,1,0 -disks_radius 0.5 -box -1,-1,2,1 -wall_box_bottom_material 1", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, s->frictional, "frictional = TRUE once a wall of material 1 can touch the disks"));
  PetscCall(KergsSceneDestroy(&s));
  PetscCall(SceneGood(comm, "-friction 0.3 -disks_x 0,0 -disks_radius 0.5", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)!s->frictional, "frictional = FALSE for a single disk without walls"));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestLattice(MPI_Comm comm)
{
  KergsScene s;
  Disks      all;
  PetscReal  dmin;
  PetscInt   nat;
  PetscBool  overlap;
  char       what[256];

  PetscFunctionBeginUser;
  /* square 4 x 3: touching pairs 3 * 3 in rows + 4 * 2 in columns = 17 */
  PetscCall(SceneGood(comm, "-disks_source lattice -lattice_n 4,3 -lattice_radius 0.1 -lattice_origin 1,2", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(DisksGather(s, &all));
  PetscCall(PairStats(&all, 0.2, 1e-12, &dmin, &nat, &overlap));
  PetscCall(CheckTrue(comm, (PetscBool)(s->ndisks == 12 && all.x[0] == 1.0 && all.x[1] == 2.0),
                      "square lattice: 12 disks, the first at the origin"));
  PetscCall(DisksFree(&all));
  PetscCall(PetscSNPrintf(what, sizeof(what),
                          "square lattice: nearest-neighbour distance 2r = 0.2 (%.17g), 17 touching pairs (%" PetscInt_FMT ")",
                          (double)dmin, nat));
  PetscCall(CheckTrue(comm, (PetscBool)(Close(dmin, 0.2, 1e-12) && nat == 17 && !overlap), what));
  PetscCall(CheckOwnership(s));
  PetscCall(KergsSceneDestroy(&s));
  /* hex 4 x 3: 3 * 3 in rows + 2 row gaps * (2 * 4 - 1) = 23 touching pairs */
  PetscCall(SceneGood(comm, "-disks_source lattice -lattice_type hex -lattice_n 4,3 -lattice_radius 0.1", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(DisksGather(s, &all));
  PetscCall(PairStats(&all, 0.2, 1e-12, &dmin, &nat, &overlap));
  PetscCall(DisksFree(&all));
  PetscCall(PetscSNPrintf(what, sizeof(what),
                          "hex lattice: nearest-neighbour distance 2r = 0.2 (%.17g), 23 touching pairs (%" PetscInt_FMT ")", (double)dmin,
                          nat));
  PetscCall(CheckTrue(comm, (PetscBool)(s->ndisks == 12 && Close(dmin, 0.2, 1e-12) && nat == 23 && !overlap), what));
  PetscCall(KergsSceneDestroy(&s));
  /* a larger spacing: no contact */
  PetscCall(SceneGood(
      comm, "-disks_source lattice -lattice_type hex -lattice_n 3,3 -lattice_radius 0.1 -lattice_spacing 0.25 -disks_material 0", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(DisksGather(s, &all));
  PetscCall(PairStats(&all, 0.25, 1e-12, &dmin, &nat, &overlap));
  PetscCall(DisksFree(&all));
  PetscCall(
      CheckTrue(comm, (PetscBool)(Close(dmin, 0.25, 1e-12) && nat == 16), "hex lattice with -lattice_spacing: neighbours at the spacing"));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* A checksum of the (gathered) disks that depends on their order, positions and radii. */
static PetscReal Checksum(const Disks *s)
{
  PetscReal sum = 0.0;

  for (PetscInt i = 0; i < s->n; i++) sum += (i + 1) * (s->x[2 * i] + 3.0 * s->x[2 * i + 1] + 7.0 * s->radius[i]);
  return sum;
}

static PetscErrorCode TestRandom(MPI_Comm comm)
{
  const char *opts = "-disks_source random -random_n 300 -random_box 0,0,1,1 -random_radius 0.01,0.02 -random_seed %d";
  char        buf[256];
  KergsScene  s, same, other;
  Disks       all, allsame, allother;
  PetscReal   dmin, rmin = PETSC_MAX_REAL, rmax = 0.0, sum, sums[2];
  PetscInt    nat;
  PetscBool   overlap, inside = PETSC_TRUE, identical;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(buf, sizeof(buf), opts, 7));
  PetscCall(SceneGood(comm, buf, &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(SceneGood(comm, buf, &same));
  if (!same) PetscFunctionReturn(0);
  PetscCall(PetscSNPrintf(buf, sizeof(buf), opts, 8));
  PetscCall(SceneGood(comm, buf, &other));
  if (!other) PetscFunctionReturn(0);
  PetscCall(DisksGather(s, &all));
  PetscCall(DisksGather(same, &allsame));
  PetscCall(DisksGather(other, &allother));
  PetscCall(PairStats(&all, 1.0, 0.0, &dmin, &nat, &overlap));
  for (PetscInt i = 0; i < all.n; i++) {
    rmin = PetscMin(rmin, all.radius[i]);
    rmax = PetscMax(rmax, all.radius[i]);
    for (PetscInt d = 0; d < 2; d++)
      if (all.x[2 * i + d] - all.radius[i] < 0.0 || all.x[2 * i + d] + all.radius[i] > 1.0) inside = PETSC_FALSE;
  }
  PetscCall(CheckTrue(comm, (PetscBool)(s->ndisks == 300 && !overlap), "random: 300 disks, no two overlap (brute force)"));
  PetscCall(CheckTrue(comm, (PetscBool)(rmin >= 0.01 && rmax <= 0.02 && rmax - rmin > 0.005), "random: radii spread within [rmin, rmax]"));
  PetscCall(CheckTrue(comm, inside, "random: every disk inside -random_box"));
  sum = Checksum(&all);
  PetscCallMPI(MPI_Allreduce(&sum, &sums[0], 1, MPIU_REAL, MPIU_MIN, comm));
  PetscCallMPI(MPI_Allreduce(&sum, &sums[1], 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(CheckTrue(comm, (PetscBool)(sums[0] == sums[1]), "random: the same sample on every rank (checksum min == max)"));
  identical = (same->ndisks == s->ndisks) ? PETSC_TRUE : PETSC_FALSE;
  for (PetscInt i = 0; identical && i < all.n; i++)
    if (allsame.x[2 * i] != all.x[2 * i] || allsame.x[2 * i + 1] != all.x[2 * i + 1] || allsame.radius[i] != all.radius[i])
      identical = PETSC_FALSE;
  PetscCall(CheckTrue(comm, identical, "random: same seed, same sample (bitwise)"));
  PetscCall(CheckTrue(comm, (PetscBool)(other->ndisks == 300 && Checksum(&allother) != sum),
                      "random: a different seed gives a different sample"));
  PetscCall(DisksFree(&all));
  PetscCall(DisksFree(&allsame));
  PetscCall(DisksFree(&allother));
  PetscCall(CheckOwnership(s));
  PetscCall(KergsSceneDestroy(&s));
  PetscCall(KergsSceneDestroy(&same));
  PetscCall(KergsSceneDestroy(&other));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestWalls(MPI_Comm comm)
{
  const char *names[4] = {"box_bottom", "box_right", "box_top", "box_left"};
  KergsScene  s;
  PetscBool   inward = PETSC_TRUE, named = PETSC_TRUE;
  PetscReal   v[2];

  PetscFunctionBeginUser;
  PetscCall(SceneGood(comm, "-box 0,0,2,1 -disks_x 1,0.5 -disks_radius 0.1", &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)(s->nwalls == 4), "box: 4 walls"));
  for (PetscInt w = 0; w < s->nwalls; w++) {
    const KergsWall *wall = &s->walls[w];
    const PetscReal  tx = wall->b[0] - wall->a[0], ty = wall->b[1] - wall->a[1];
    const PetscReal  nx = -ty, ny = tx; /* left normal of a->b */
    const PetscReal  mx = 0.5 * (wall->a[0] + wall->b[0]), my = 0.5 * (wall->a[1] + wall->b[1]);
    PetscBool        same;

    if (nx * (1.0 - mx) + ny * (0.5 - my) <= 0.0) inward = PETSC_FALSE; /* towards the centre (1, 0.5) */
    if (wall->kind != KERGS_WALL_DRIVEN || wall->nprog != 0 || wall->v[0] != 0.0 || wall->v[1] != 0.0) inward = PETSC_FALSE;
    PetscCall(PetscStrcmp(wall->name, names[w], &same));
    if (!same) named = PETSC_FALSE;
  }
  PetscCall(CheckTrue(comm, inward, "box: driven walls at rest whose outward normals point into the box"));
  PetscCall(CheckTrue(comm, named, "box: walls named box_bottom, box_right, box_top, box_left"));
  PetscCall(KergsSceneDestroy(&s));

  PetscCall(
      SceneGood(comm,
                "-box 0,0,2,1 -box_open_top -wall_box_right_type free -wall_box_right_mass 5 -wall_box_right_force -1,0 "
                "-wall_box_right_velocity -0.5,0 "
                "-walls piston,floor -wall_piston_a 2,1 -wall_piston_b 0,1 -wall_piston_program 0.5,0,-1,1.0,0,2,2.0,0,0 "
                "-wall_floor_a -5,-1 -wall_floor_b 5,-1 -wall_floor_infinite -wall_floor_velocity 0.25,0 -disks_x 1,0.5 -disks_radius 0.1",
                &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)(s->nwalls == 5), "open box + 2 declared walls: 5 walls"));
  PetscCall(CheckTrue(comm,
                      (PetscBool)(s->walls[1].kind == KERGS_WALL_FREE && s->walls[1].mass == 5.0 && s->walls[1].force[0] == -1.0 &&
                                  s->walls[1].v[0] == -0.5),
                      "box wall overridden into a free wall with mass, force and initial velocity"));
  {
    const PetscReal t[]  = {0.0, 0.49, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0};
    const PetscReal vy[] = {0.0, 0.0, -1.0, -1.0, 2.0, 2.0, 0.0, 0.0};
    PetscBool       ok   = (PetscBool)(s->walls[3].nprog == 3);

    for (PetscInt k = 0; k < 8; k++) {
      PetscCall(KergsWallVelocityAt(&s->walls[3], t[k], v));
      if (v[0] != 0.0 || v[1] != vy[k]) ok = PETSC_FALSE;
    }
    PetscCall(CheckTrue(comm, ok, "piston program: 0 before 0.5, -1 on [0.5,1), 2 on [1,2), 0 after 2"));
  }
  PetscCall(KergsWallVelocityAt(&s->walls[4], 10.0, v));
  PetscCall(CheckTrue(comm, (PetscBool)(s->walls[4].infinite && v[0] == 0.25 && v[1] == 0.0 && s->walls[4].v[0] == 0.25),
                      "floor: infinite, constant velocity program"));
  PetscCall(KergsWallVelocityAt(&s->walls[1], 10.0, v));
  PetscCall(CheckTrue(comm, (PetscBool)(v[0] == -0.5), "free wall: VelocityAt gives its current velocity"));
  PetscCall(KergsSceneView(s, PETSC_VIEWER_STDOUT_(comm)));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* Pressure-controlled walls: force = pressure x loaded length along the inward normal. A box wall's length is the
   separation of the two box walls perpendicular to it, an oblique wall's its own |b - a|, and the force follows the
   spanning walls when they move (here through KergsSceneRestoreWall, as a restart moves them). */
static PetscErrorCode TestPressureWalls(MPI_Comm comm)
{
  KergsScene s;
  PetscReal  len[4];

  PetscFunctionBeginUser;
  PetscCall(SceneGood(comm,
                      "-box 0,0,2,1 -wall_box_right_type free -wall_box_right_mass 1 -wall_box_right_pressure 3 "
                      "-wall_box_top_type free -wall_box_top_mass 1 -wall_box_top_pressure 3 "
                      "-walls lone -wall_lone_a 5,5 -wall_lone_b 8,9 -wall_lone_type free -wall_lone_mass 1 -wall_lone_pressure 2 "
                      "-disks_x 1,0.5 -disks_radius 0.1",
                      &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(KergsSceneWallLoadedLength(s, 1, &len[0]));
  PetscCall(KergsSceneWallLoadedLength(s, 2, &len[1]));
  PetscCall(KergsSceneWallLoadedLength(s, 4, &len[2]));
  PetscCall(CheckTrue(comm, (PetscBool)(s->walls[1].span[0] == 0 && s->walls[1].span[1] == 2 && Close(len[0], 1.0, 1e-15)),
                      "pressure: box_right spans box_bottom to box_top, length 1"));
  PetscCall(CheckTrue(comm, (PetscBool)(s->walls[2].span[0] == 1 && s->walls[2].span[1] == 3 && Close(len[1], 2.0, 1e-15)),
                      "pressure: box_top spans box_right to box_left, length 2"));
  PetscCall(CheckTrue(comm, (PetscBool)(s->walls[4].span[0] == -1 && Close(len[2], 5.0, 1e-15)),
                      "pressure: an oblique wall without perpendicular walls takes its own length 5"));
  PetscCall(CheckTrue(comm, (PetscBool)(Close(s->walls[1].force[0], -3.0, 1e-15) && s->walls[1].force[1] == 0.0),
                      "pressure: box_right pushed inward by 3 x 1"));
  PetscCall(CheckTrue(comm, (PetscBool)(Close(s->walls[2].force[1], -6.0, 1e-15) && PetscAbsReal(s->walls[2].force[0]) < 1e-15),
                      "pressure: box_top pushed inward by 3 x 2"));
  PetscCall(CheckTrue(comm, (PetscBool)(Close(s->walls[4].force[0], -8.0, 1e-14) && Close(s->walls[4].force[1], 6.0, 1e-14)),
                      "pressure: the oblique wall pushed along its normal (-0.8, 0.6) by 2 x 5"));
  PetscCall(CheckTrue(comm, (PetscBool)(s->walls[1].guided && s->walls[2].guided && s->walls[4].guided && !s->walls[0].guided),
                      "pressure: a pressure wall is guided along its normal by default"));
  {
    const PetscReal a[2] = {2, 0.4}, b[2] = {0, 0.4}, v[2] = {0, 0}, disp[2] = {0, -0.6};
    PetscCall(KergsSceneRestoreWall(s, 2, a, b, v, disp)); /* box_top lowered to y = 0.4 */
  }
  PetscCall(KergsSceneWallLoadedLength(s, 1, &len[3]));
  PetscCall(CheckTrue(comm, (PetscBool)(Close(len[3], 0.4, 1e-15) && Close(s->walls[1].force[0], -1.2, 1e-15)),
                      "pressure: box_right's length and force follow box_top (0.4, -1.2)"));
  PetscCall(KergsSceneView(s, PETSC_VIEWER_STDOUT_(comm)));
  PetscCall(KergsSceneDestroy(&s));

  PetscCall(SceneGood(comm,
                      "-box 0,0,2,1 -box_open_top -wall_box_right_type free -wall_box_right_mass 1 -wall_box_right_pressure 3 "
                      "-disks_x 1,0.5 -disks_radius 0.1",
                      &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(CheckTrue(comm, (PetscBool)(s->walls[1].span[0] == -1 && Close(s->walls[1].force[0], -3.0, 1e-15)),
                      "pressure: an open box's side wall has no top, its own length 1"));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* A guided wall's force typed to 6 digits along an oblique normal (-2, 1)/sqrt(5) is accepted and taken along it:
   no component along the wall is left to drive it there. */
static PetscErrorCode TestGuidedForce(MPI_Comm comm)
{
  KergsScene s;
  PetscReal  n[KERGS_DIM], ft;

  PetscFunctionBeginUser;
  PetscCall(
      SceneGood(comm,
                "-walls w -wall_w_a 2,0 -wall_w_b 3,2 -wall_w_type free -wall_w_mass 1 -wall_w_guided -wall_w_force -0.894427,0.447214 "
                "-wall_w_velocity -2e-6,1e-6 -disks_x 0,0 -disks_radius 0.1",
                &s));
  if (!s) PetscFunctionReturn(0);
  KergsWallNormal(&s->walls[0], n);
  ft = -n[1] * s->walls[0].force[0] + n[0] * s->walls[0].force[1];
  PetscCall(CheckTrue(comm,
                      (PetscBool)(PetscAbsReal(ft) < 1e-15 && PetscAbsReal(-n[1] * s->walls[0].v[0] + n[0] * s->walls[0].v[1]) < 1e-21 &&
                                  Close(s->walls[0].force[0] * n[0] + s->walls[0].force[1] * n[1], 1.0, 1e-6)),
                      "guided: a force and a velocity typed to 6 digits are taken along the oblique normal"));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* -box_affine_start: each grain's velocity plus the box walls' velocities interpolated across the box, the top wall's
   program read at the scene's start; a box at rest leaves the velocities as given. */
static PetscErrorCode TestAffineStart(MPI_Comm comm)
{
  const char     *box        = "-box 0,0,4,2 -wall_box_top_program 0,0,-0.5,1,0,-9 -wall_box_right_velocity 0.3,0 "
                               "-disks_x 1,1.5,3,0.5,2,1 -disks_radius 0.1 -disks_velocity 0,0,0.01,0,0,0";
  const PetscReal want[3][2] = {{0.25 * 0.3, 0.75 * -0.5}, {0.01 + 0.75 * 0.3, 0.25 * -0.5}, {0.5 * 0.3, 0.5 * -0.5}};
  char            opts[512];
  KergsScene      s;
  Disks           all;
  PetscBool       ok = PETSC_TRUE;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts), "%s -box_affine_start", box));
  PetscCall(SceneGood(comm, opts, &s));
  if (!s) PetscFunctionReturn(0);
  PetscCall(DisksGather(s, &all));
  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt d = 0; d < 2; d++) ok = (PetscBool)(ok && Close(all.v[2 * i + d], want[i][d], 1e-15));
  PetscCall(CheckTrue(comm, ok, "affine start: v = own + the box walls' velocities interpolated (x: left 0 to right 0.3, y: 0 to -0.5)"));
  PetscCall(DisksFree(&all));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* KergsSceneSetDisks directly, and the kinetic energy. */
static PetscErrorCode TestSetDisksEnergy(MPI_Comm comm)
{
  const PetscReal x[] = {0, 0, 2, 0, 4, 0}, r[] = {0.5, 0.5, 1.0}, v[] = {3, 4, 0, 1, 0, 0};
  const PetscInt  mat[] = {0, 0, 0};
  KergsScene      s;
  Disks           all;
  PetscReal       ek, vmax, m, inertia;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneCreate(comm, &s));
  s->density[0] = 2.0;
  PetscCall(KergsSceneSetDisks(s, 3, x, r, mat, v));
  m       = 2.0 * PETSC_PI * 0.25;
  inertia = 0.5 * m * 0.25;
  if (s->dstart == 0 && s->nowned > 0) s->omega[0] = 2.0; /* disk 0, on its owner */
  PetscCall(KergsSceneKineticEnergy(s, &ek, &vmax));
  PetscCall(CheckTrue(comm, (PetscBool)(Close(ek, 0.5 * m * 26.0 + 0.5 * inertia * 4.0, 1e-14) && vmax == 5.0),
                      "kinetic energy 1/2 m v^2 + 1/2 I w^2 and largest speed"));
  PetscCall(DisksGather(s, &all));
  PetscCall(CheckTrue(comm,
                      (PetscBool)(Close(all.mass[0], m, 1e-14) && Close(all.mass[2], 2.0 * PETSC_PI, 1e-14) &&
                                  Close(all.inertia[0], inertia, 1e-14) && Close(s->alert, 0.1 * 2.0 / 3.0, 1e-14)),
                      "SetDisks: masses from density, alert from mean radius"));
  PetscCall(CheckTrue(comm,
                      (PetscBool)(all.x[2] == 2.0 && all.radius[2] == 1.0 && all.v[0] == 3.0 && all.v[3] == 1.0 && all.id[1] == 1 &&
                                  all.omega[0] == 2.0 && all.omega[1] == 0.0),
                      "SetDisks: each rank keeps its slice of the full arrays, gathered back in global-index order"));
  PetscCall(DisksFree(&all));
  PetscCall(CheckOwnership(s));
  PetscCall(KergsSceneCheck(s));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* Each bad input must fail with a message that names the fault. */
static PetscErrorCode TestErrors(MPI_Comm comm)
{
  const char *cases[][2] = {
      {"", "no disks and no walls"},
      {"-disks_x 0,0,1,1 -disks_radius 1,-0.5", "Grain 1: radius -0.5"},
      {"-disks_x 0,0 -disks_radius 0", "Grain 0: radius 0"},
      {"-disks_x 0,0 -disks_radius inf", "Grain 0: radius inf"},
      {"-disks_x 0,0,1,nan -disks_radius 0.1", "Grain 1: position"},
      {"-disks_x 0,inf -disks_radius 0.1", "Grain 0: position"},
      {"-disks_x 0,0,1,1 -disks_radius 0.1 -disks_velocity 0,0,nan,0", "Grain 1: velocity"},
      {"-disks_x 0,0 -disks_radius 0.1 -material_density 0", "density of material 0"},
      {"-disks_x 0,0 -disks_radius 0.1 -materials 2 -material_density 1,-2", "density of material 1"},
      {"-disks_x 0,0 -disks_radius 0.1 -friction -0.1", "friction coefficient"},
      {"-disks_x 0,0 -disks_radius 0.1 -materials 2 -friction_pairs 0,1,nan", "materials (0, 1)"},
      {"-disks_x 0,0 -disks_radius 0.1 -dt 0", "-dt 0"},
      {"-disks_x 0,0 -disks_radius 0.1 -dt -1e-3", "-dt"},
      {"-disks_x 0,0 -disks_radius 0.1 -theta 0", "-theta"},
      {"-disks_x 0,0 -disks_radius 0.1 -theta 1.5", "-theta"},
      {"-disks_x 0,0 -disks_radius 0.1 -steps -1", "-steps"},
      {"-disks_x 0,0 -disks_radius 0.1 -alert -1", "-alert"},
      {"-disks_x 0,0 -disks_radius 0.1 -alert -2", "-alert"}, /* PETSC_DEFAULT's value typed as a number */
      {"-walls w -wall_w_a 1,1 -wall_w_b 1,1", "Wall w is degenerate"},
      {"-walls w -wall_w_a 0,0", "-wall_w_b"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free", "Free wall w: mass"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass -2", "Free wall w: mass"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_program 1,0,0,0.5,0,0", "times must increase"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_program 1,0", "-wall_w_program"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_program 1,0,0 -wall_w_velocity 1,0", "not both"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_pressure 5", "Wall w is driven: -wall_w_pressure"},
      {"-disks_x 0.5,0.5 -disks_radius 0.1 -box 0,0,1,1 -wall_box_left_pressure 5", "Wall box_left is driven"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass 1 -wall_w_pressure -1", "-wall_w_pressure -1"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass 1 -wall_w_pressure inf", "-wall_w_pressure inf"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass 1 -wall_w_pressure nan", "-wall_w_pressure nan"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass 1 -wall_w_pressure 5 -wall_w_force 1,0",
       "-wall_w_pressure or -wall_w_force, not both"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_pressure 5", "Free wall w: mass"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_guided", "Wall w is driven: -wall_w_guided"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass 1 -wall_w_guided -wall_w_force 1,1",
       "its force (1, 1) has a component 0.707107 of its size along the wall, above 1e-06"},
      {"-walls w -wall_w_a 0,0 -wall_w_b 1,0 -wall_w_type free -wall_w_mass 1 -wall_w_pressure 5 -wall_w_velocity 1,0",
       "its velocity (1, 0) has a component 1. of its size along the wall"},
      {"-walls w -wall_w_a 2,0 -wall_w_b 3,2 -wall_w_type free -wall_w_mass 1 -wall_w_guided -wall_w_force -1,0",
       "its force (-1, 0) has a component -0.447214 of its size"},
      {"-walls w,w -wall_w_a 0,0 -wall_w_b 1,0", "used twice"},
      {"-walls w -wall_w_a 0,0,1 -wall_w_b 1,0", "-wall_w_a"},
      {"-disks_x 0,0 -disks_radius 0.1 -disks_material 1", "Grain 0 has material 1"},
      {"-disks_x 0,0 -disks_radius 0.1 -box 0,0,1,1 -wall_box_left_material 3", "Wall box_left: material"},
      {"-disks_x 0,0,1 -disks_radius 0.1", "-disks_x has 3 values"},
      {"-disks_x 0,0,1,1,2,2 -disks_radius 0.1,0.2", "-disks_radius has 2"},
      {"-disks_x 0,0,1,1 -disks_radius 0.1 -disks_velocity 1,1", "-disks_velocity has 2"},
      {"-disks_x 0,0,1,1 -disks_radius 0.1 -disks_material 0,0,0", "-disks_material has 3"},
      {"-disks_radius 0.1", "without -disks_x"},
      {"-disks_x 0,0 -disks_radius 0.1 -materials 2 -material_density 1,2,3", "-material_density has 3"},
      {"-disks_x 0,0 -disks_radius 0.1 -materials 2 -friction_pairs 0,2,0.1", "-friction_pairs"},
      {"-disks_x 0,0 -disks_radius 0.1 -friction_pairs 0,0", "-friction_pairs has 2"},
      {"-disks_x 0,0 -disks_radius 0.1 -box_affine_start", "-box_affine_start needs the four walls of -box"},
      {"-disks_x 0.5,0.5 -disks_radius 0.1 -box 0,0,1,1 -box_open_top -box_affine_start", "-box_affine_start needs the four walls"},
      {"-disks_x 0.5,0.5 -disks_radius 0.1 -box 0,0,1,1 -wall_box_top_velocity 0,nan -box_affine_start",
       "box wall's velocity is not finite"},
      {"-disks_x 0,0 -disks_radius 0.1 -materials 0", "-materials 0"},
      {"-disks_source foo -disks_x 0,0 -disks_radius 0.1", "foo"},
      {"-disks_source lattice -lattice_n 2 -lattice_radius 0.1", "-lattice_n"},
      {"-disks_source lattice -lattice_n 2,2", "-lattice_radius"},
      {"-disks_source lattice -lattice_n 2,2 -lattice_radius 0.1 -lattice_spacing 0.1", "-lattice_spacing"},
      {"-disks_source random -random_n 100 -random_box 0,0,1,1 -random_radius 0.1,0.2", "fewer than -random_n"},
      {"-disks_source random -random_n 10 -random_box 0,0,1,1 -random_radius 0.2,0.1", "-random_radius"},
      {"-disks_source random -random_n 10 -random_radius 0.01,0.02", "-random_box"},
      {"-disks_x 0,0 -disks_radius 0.1 -box 0,0,1", "-box needs 4"},
      {"-disks_x 0,0 -disks_radius 0.1 -box 1,0,0,1", "x0 < x1"},
      {"-disks_x 0,0 -disks_radius 0.1 -gravity 0", "-gravity"},
  };
  const PetscInt ncases = (PetscInt)(sizeof(cases) / sizeof(cases[0]));

  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < ncases; c++) {
    KergsScene     s;
    PetscErrorCode ierr;
    const char    *msg;
    char           found[4096], what[4096];
    char          *at;

    PetscCall(SceneFromString(comm, cases[c][0], &s, &ierr, &msg));
    PetscCall(PetscStrncpy(found, msg, sizeof(found)));
    PetscCall(PetscStrstr(found, cases[c][1], &at));
    PetscCall(PetscSNPrintf(what, sizeof(what), "rejects \"%s\" with a message naming \"%s\" [%s]", cases[c][0], cases[c][1], found));
    PetscCall(CheckTrue(comm, (PetscBool)(ierr != 0 && at != NULL), what));
    PetscCall(KergsSceneDestroy(&s));
  }
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  MPI_Comm  comm;
  PetscBool from_command_line = PETSC_FALSE;

  PetscCall(PetscInitialize(&argc, &argv, NULL, "Tests of the kergs scene"));
  comm = PETSC_COMM_WORLD;
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-from_command_line", &from_command_line, NULL));
  if (from_command_line) {
    KergsScene s;

    PetscCall(KergsSceneCreate(comm, &s));
    PetscCall(KergsSceneSetFromOptions(s));
    PetscCall(KergsSceneView(s, NULL));
    PetscCall(KergsSceneDestroy(&s));
  } else {
    PetscCall(TestList(comm));
    PetscCall(TestLattice(comm));
    PetscCall(TestRandom(comm));
    PetscCall(TestWalls(comm));
    PetscCall(TestPressureWalls(comm));
    PetscCall(TestGuidedForce(comm));
    PetscCall(TestAffineStart(comm));
    PetscCall(TestSetDisksEnergy(comm));
    PetscCall(TestErrors(comm));
  }
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
