/* kergs walls: the one-sided lines and segments that confine the disks (kergs/scene.h, KergsWall): the box and the
   named walls read from the options, their velocities (a driven wall's program, a free wall's own), their motion at
   the end of a step, their checks and their view. The scene's container (src/scene/scene.c) holds them.

   A wall's kind decides how it moves: a driven wall follows its velocity program (its DOFs are in V_g), a free wall is
   a body with a mass under an applied force (its DOFs are in V_f, updated by the solve). Every function below that
   depends on the kind switches on it: KergsWallVelocityAt, WallSetProgram, WallSetFromOptions (the kind's options),
   KergsSceneAdvanceWalls, CheckWall and ViewWall; a new kind adds its case there and its name to KergsWallKinds.
   Outside the scene, the operators (V_f or V_g), the kernel and the watch (energy, work) ask whether a wall is free.
   A pressure-controlled wall is a free wall whose force the scene sets from its pressure and loaded length (WallSpan,
   UpdateWallPressures) whenever the walls move: at setup, after each step's motion and after a restart. A guided free
   wall (the default under a pressure) moves along its normal only: the operators project its rows of H_f on n. */
#include <kergs/private/sceneimpl.h>
#include <petscviewer.h>

const char *const KergsWallKinds[] = {"driven", "free", "KergsWallKind", "KERGS_WALL_", NULL};

#define KERGS_WALL_PREFIX_LEN 128

/* ------------------------------------------------------------------------------------------------ */
/* Pressure-controlled walls                                                                        */

/* Unit tangent t = (b - a)/|b - a| and left normal n = (-t_y, t_x) of a wall (it points to the disks' side). */
static void WallFrame(const KergsWall *w, PetscReal t[], PetscReal n[])
{
  const PetscReal len = PetscSqrtReal(PetscSqr(w->b[0] - w->a[0]) + PetscSqr(w->b[1] - w->a[1]));

  t[0] = len > 0.0 ? (w->b[0] - w->a[0]) / len : 0.0; /* a degenerate wall: CheckWall names it */
  t[1] = len > 0.0 ? (w->b[1] - w->a[1]) / len : 0.0;
  n[0] = -t[1];
  n[1] = t[0];
}

/* The two walls that bound the sample along wall w: a wall whose normal is +t faces along a->b (the lower bound of
   the sample along t), one whose normal is -t faces against it (the upper bound). Walls translate and never rotate,
   so the pair found at setup holds for the run. A box's wall gets the opposite pair (box_right: box_bottom and
   box_top); anything else, -1 (its own length). The tolerance accepts walls given with rounded endpoints. */
static void WallSpan(const KergsWall walls[], PetscInt nwalls, PetscInt w, PetscInt span[2])
{
  const PetscReal parallel = 1.0 - 1e-9;
  PetscReal       t[KERGS_DIM], n[KERGS_DIM];
  PetscInt        count[2] = {0, 0}, found[2] = {-1, -1};

  WallFrame(&walls[w], t, n);
  for (PetscInt k = 0; k < nwalls; k++) {
    PetscReal tk[KERGS_DIM], nk[KERGS_DIM], c;

    if (k == w) continue;
    WallFrame(&walls[k], tk, nk);
    c = nk[0] * t[0] + nk[1] * t[1];
    if (c >= parallel) found[0] = k, count[0]++;
    if (c <= -parallel) found[1] = k, count[1]++;
  }
  span[0] = count[0] == 1 && count[1] == 1 ? found[0] : -1;
  span[1] = count[0] == 1 && count[1] == 1 ? found[1] : -1;
}

/* The separation along t of the two spanning walls (zero once they cross), or the wall's own |b - a|. */
static PetscReal WallLoadedLength(const KergsWall walls[], PetscInt w)
{
  const KergsWall *wall = &walls[w];
  PetscReal        t[KERGS_DIM], n[KERGS_DIM];

  WallFrame(wall, t, n);
  if (wall->span[0] < 0 || wall->span[1] < 0) return PetscSqrtReal(PetscSqr(wall->b[0] - wall->a[0]) + PetscSqr(wall->b[1] - wall->a[1]));
  {
    const PetscReal *lo = walls[wall->span[0]].a, *hi = walls[wall->span[1]].a;
    return PetscMax(0.0, t[0] * (hi[0] - lo[0]) + t[1] * (hi[1] - lo[1]));
  }
}

void KergsWallNormal(const KergsWall *w, PetscReal n[])
{
  PetscReal t[KERGS_DIM];

  WallFrame(w, t, n);
}

void KergsWallOnNormal(const KergsWall *w, PetscReal v[])
{
  PetscReal t[KERGS_DIM], n[KERGS_DIM], vn = 0.0;

  WallFrame(w, t, n);
  for (PetscInt d = 0; d < KERGS_DIM; d++) vn += v[d] * n[d];
  for (PetscInt d = 0; d < KERGS_DIM; d++) v[d] = vn * n[d] + 0.0; /* + 0.0: no -0 in the view */
}

PetscErrorCode KergsSceneWallLoadedLength(KergsScene scene, PetscInt w, PetscReal *length)
{
  PetscFunctionBeginUser;
  PetscCheck(w >= 0 && w < scene->nwalls, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene %s: no wall %" PetscInt_FMT " (it has %" PetscInt_FMT ")", scene->name, w, scene->nwalls);
  *length = WallLoadedLength(scene->walls, w);
  PetscFunctionReturn(0);
}

/* force = pressure x loaded length x n: the pressure pushes the wall towards the disks. Explicit in the length: a step
   uses the length at its start (the biaxial test's lateral stress, constant to O(dt v_wall / L) per step). */
static void UpdateWallPressures(KergsScene sc)
{
  for (PetscInt w = 0; w < sc->nwalls; w++) {
    KergsWall *wall = &sc->walls[w];
    PetscReal  t[KERGS_DIM], n[KERGS_DIM], f;

    if (!wall->has_pressure) continue;
    WallFrame(wall, t, n);
    f = wall->pressure * WallLoadedLength(sc->walls, w);
    for (PetscInt d = 0; d < KERGS_DIM; d++) wall->force[d] = f * n[d];
  }
}

/* ------------------------------------------------------------------------------------------------ */
/* Velocities and motion                                                                            */

/* Driven wall: the value of its piecewise-constant program at time t, piece k holding on [t_k, t_{k+1}) and the
   last piece forever; zero before t_0 and for a wall without program. Free wall: its current velocity. */
PetscErrorCode KergsWallVelocityAt(const KergsWall *wall, PetscReal t, PetscReal v[])
{
  PetscFunctionBeginUser;
  if (wall->kind == KERGS_WALL_FREE) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) v[d] = wall->v[d];
    PetscFunctionReturn(0);
  }
  for (PetscInt d = 0; d < KERGS_DIM; d++) v[d] = 0.0;
  for (PetscInt k = 0; k < wall->nprog && t >= wall->prog_t[k]; k++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) v[d] = wall->prog_v[k][d];
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneSetWallVelocity(KergsScene scene, PetscInt w, const PetscReal v[])
{
  PetscFunctionBeginUser;
  PetscCheck(w >= 0 && w < scene->nwalls, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene %s: no wall %" PetscInt_FMT " (it has %" PetscInt_FMT ")", scene->name, w, scene->nwalls);
  for (PetscInt d = 0; d < KERGS_DIM; d++) scene->walls[w].v[d] = v[d];
  PetscFunctionReturn(0);
}

/* x+ = x- + dt (theta V+ + (1 - theta) V-) for the free walls; a driven wall moves with its given velocity of the step. */
PetscErrorCode KergsSceneAdvanceWalls(KergsScene sc, const PetscReal wvold[])
{
  const PetscReal th = sc->theta, dt = sc->dt;

  PetscFunctionBeginUser;
  for (PetscInt w = 0; w < sc->nwalls; w++) {
    KergsWall *wall = &sc->walls[w];
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      PetscReal dx = wall->kind == KERGS_WALL_DRIVEN ? dt * wall->v[d] : dt * (th * wall->v[d] + (1 - th) * wvold[KERGS_DIM * w + d]);
      wall->a[d] += dx;
      wall->b[d] += dx;
      wall->disp[d] += dx;
    }
  }
  UpdateWallPressures(sc);
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Accessors and restart                                                                            */

PetscErrorCode KergsSceneGetWalls(KergsScene scene, PetscInt *nwalls, const KergsWall **walls)
{
  PetscFunctionBeginUser;
  if (nwalls) *nwalls = scene->nwalls;
  if (walls) *walls = scene->walls;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetBox(KergsScene scene, PetscBool *has, PetscReal box[4])
{
  /* box[k] is coordinate axis[k] of the wall named names[k]: x0 of box_left, y0 of box_bottom, ... */
  const char    *names[4] = {"box_left", "box_bottom", "box_right", "box_top"};
  const PetscInt axis[4]  = {0, 1, 0, 1};
  PetscInt       found    = 0;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 4; k++)
    for (PetscInt w = 0; w < scene->nwalls; w++) {
      PetscBool same;

      PetscCall(PetscStrcmp(scene->walls[w].name, names[k], &same));
      if (!same) continue;
      box[k] = scene->walls[w].a[axis[k]];
      found++;
    }
  *has = found == 4 ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetWallNames(KergsScene scene, char **joined)
{
  size_t len = 1;

  PetscFunctionBeginUser;
  for (PetscInt w = 0; w < scene->nwalls; w++) len += strlen(scene->walls[w].name) + 1;
  PetscCall(PetscCalloc1(len, joined));
  for (PetscInt w = 0; w < scene->nwalls; w++) {
    if (w) PetscCall(PetscStrlcat(*joined, ",", len));
    PetscCall(PetscStrlcat(*joined, scene->walls[w].name, len));
  }
  PetscFunctionReturn(0);
}

/* The velocity at the scene's time of the box wall `name` (zero when there is none). */
static PetscErrorCode BoxWallVelocity(KergsScene scene, const char name[], PetscReal v[])
{
  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < KERGS_DIM; d++) v[d] = 0.0;
  for (PetscInt w = 0; w < scene->nwalls; w++) {
    PetscBool same;

    PetscCall(PetscStrcmp(scene->walls[w].name, name, &same));
    if (same) PetscCall(KergsWallVelocityAt(&scene->walls[w], scene->time, v));
  }
  PetscFunctionReturn(0);
}

/* Adds to each owned grain's velocity the box walls' normal velocities interpolated linearly across the box: v_x from
   box_left's to box_right's x-velocity, v_y from box_bottom's to box_top's y-velocity (a free wall's is its current
   velocity, zero at a start). A top wall driven into a sample at rest otherwise pushes the column's momentum into it in
   the first steps, which at 10^6 disks is felt as a shock (docs/biaxial.md, "The strain rate"). */
PetscErrorCode KergsSceneBoxAffineStart(KergsScene scene)
{
  PetscBool has;
  PetscReal box[4], vl[KERGS_DIM], vr[KERGS_DIM], vb[KERGS_DIM], vt[KERGS_DIM];

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetBox(scene, &has, box));
  PetscCheck(has, scene->comm, PETSC_ERR_ARG_WRONGSTATE, "-box_affine_start needs the four walls of -box (or -box_from_sample)");
  PetscCall(BoxWallVelocity(scene, "box_left", vl));
  PetscCall(BoxWallVelocity(scene, "box_right", vr));
  PetscCall(BoxWallVelocity(scene, "box_bottom", vb));
  PetscCall(BoxWallVelocity(scene, "box_top", vt));
  PetscCheck(KergsSceneFinite(vl[0]) && KergsSceneFinite(vr[0]) && KergsSceneFinite(vb[1]) && KergsSceneFinite(vt[1]), scene->comm,
             PETSC_ERR_ARG_OUTOFRANGE,
             "-box_affine_start: a box wall's velocity is not finite (box_left %g, box_right %g, box_bottom %g, box_top %g)", (double)vl[0],
             (double)vr[0], (double)vb[1], (double)vt[1]);
  for (PetscInt i = 0; i < scene->nowned; i++) {
    const PetscReal sx = (scene->x[KERGS_DIM * i] - box[0]) / (box[2] - box[0]);
    const PetscReal sy = (scene->x[KERGS_DIM * i + 1] - box[1]) / (box[3] - box[1]);

    scene->v[KERGS_DIM * i] += vl[0] + sx * (vr[0] - vl[0]);
    scene->v[KERGS_DIM * i + 1] += vb[1] + sy * (vt[1] - vb[1]);
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneRestoreWall(KergsScene scene, PetscInt w, const PetscReal a[], const PetscReal b[], const PetscReal v[],
                                     const PetscReal disp[])
{
  PetscFunctionBeginUser;
  PetscCheck(w >= 0 && w < scene->nwalls, scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene %s: no wall %" PetscInt_FMT " (it has %" PetscInt_FMT ")", scene->name, w, scene->nwalls);
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    scene->walls[w].a[d]    = a[d];
    scene->walls[w].b[d]    = b[d];
    scene->walls[w].v[d]    = v[d];
    scene->walls[w].disp[d] = disp[d];
  }
  UpdateWallPressures(scene);
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Options                                                                                          */

/* -box, -box_from_sample, -box_open_top, -box_affine_start and -walls, inside the scene's options block. */
PetscErrorCode KergsSceneWallsOptions(PetscOptionItems *PetscOptionsObject, KergsWallsSpec *spec)
{
  PetscFunctionBeginUser;
  *spec = (KergsWallsSpec){.box = {0, 0, 1, 1}}; /* the unit box, shown by -help */
  PetscCall(KergsOptionsReals(PetscOptionsObject, "-box",
                              "Box x0,y0,x1,y1: driven walls box_bottom, box_right, box_top, box_left facing inward", 4, spec->box,
                              &spec->box_set));
  PetscCall(
      KergsOptionsBool(PetscOptionsObject, "-box_from_sample",
                       "Box from the sample file of -sample_input: where the run that wrote it left its four box walls (instead of -box)",
                       NULL, spec->box_from_sample, &spec->box_from_sample, NULL));
  PetscCall(
      KergsOptionsBool(PetscOptionsObject, "-box_open_top", "Omit the top wall of -box", NULL, spec->open_top, &spec->open_top, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-box_affine_start",
                             "Start the grains in the homogeneous deformation the box walls impose: add to each grain's velocity the "
                             "box walls' normal velocities interpolated linearly across the box (x between box_left and box_right, y "
                             "between box_bottom and box_top; a free wall's is zero at the start)",
                             NULL, spec->affine_start, &spec->affine_start, NULL));
  PetscCall(KergsOptionsStringList(PetscOptionsObject, "-walls", "Names of further walls, each set by -wall_<name>_a, _b, _type, ...",
                                   &spec->nnames, &spec->names, NULL));
  PetscFunctionReturn(0);
}

/* -box_from_sample: the box a compaction ended in, recorded with its sample, so that the test that starts from the
   sample confines it exactly (a box typed by hand from another seed's sample would cut grains or leave a gap). */
static PetscErrorCode WallsBoxFromSample(MPI_Comm comm, KergsWallsSpec *spec, PetscBool restoring)
{
  char      path[PETSC_MAX_PATH_LEN], source[16];
  PetscBool set, is_file;

  PetscFunctionBeginUser;
  PetscCheck(!spec->box_set, comm, PETSC_ERR_ARG_INCOMP, "Give -box or -box_from_sample, not both");
  PetscCall(KergsSceneDisksSourceFromOptions(source, sizeof(source)));
  PetscCall(PetscStrcmp(source, "file", &is_file));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-sample_input", path, sizeof(path), &set));
  PetscCheck(is_file && set && path[0], comm, PETSC_ERR_ARG_WRONGSTATE,
             "-box_from_sample takes the box of the sample the disks come from: it needs -disks_source file -sample_input <path>");
  if (restoring) {
    PetscBool readable;
    PetscCall(PetscTestFile(path, 'r', &readable));
    PetscCheck(readable, comm, PETSC_ERR_FILE_OPEN,
               "Restart of a run with -box_from_sample: the box walls are built from its sample file %s (then moved where the checkpoint "
               "has them), which cannot be read from here; restart in the directory the run started in, with the sample where it was",
               path);
  }
  PetscCall(KergsSampleReadBox(comm, path, spec->box));
  spec->box_set = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* -box x0,y0,x1,y1: four driven walls at rest whose left normals point into the box. */
static PetscErrorCode SceneBoxWalls(KergsScene scene, const PetscReal box[4], PetscBool open_top, PetscInt *nbox, KergsWall walls[])
{
  const char     *names[4] = {"box_bottom", "box_right", "box_top", "box_left"};
  const PetscReal x0 = box[0], y0 = box[1], x1 = box[2], y1 = box[3];
  /* corners counter-clockwise: (x0,y0) (x1,y0) (x1,y1) (x0,y1); wall k goes from corner k to corner k+1 */
  const PetscReal cx[4] = {x0, x1, x1, x0}, cy[4] = {y0, y0, y1, y1};

  PetscFunctionBeginUser;
  PetscCheck(x1 > x0 && y1 > y0, scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "-box %g,%g,%g,%g: need x0 < x1 and y0 < y1", (double)x0,
             (double)y0, (double)x1, (double)y1);
  *nbox = 0;
  for (PetscInt k = 0; k < 4; k++) {
    KergsWall *w = &walls[*nbox];

    if (k == 2 && open_top) continue;
    PetscCall(PetscMemzero(w, sizeof(*w)));
    PetscCall(PetscStrncpy(w->name, names[k], sizeof(w->name)));
    w->kind = KERGS_WALL_DRIVEN;
    w->a[0] = cx[k];
    w->a[1] = cy[k];
    w->b[0] = cx[(k + 1) % 4];
    w->b[1] = cy[(k + 1) % 4];
    (*nbox)++;
  }
  PetscFunctionReturn(0);
}

/* Fill a wall's program from -wall_<name>_velocity (constant from t = 0) or -wall_<name>_program t,vx,vy,... */
static PetscErrorCode WallSetProgram(MPI_Comm comm, KergsWall *w, const PetscReal vel[], PetscBool vset, PetscInt nvals,
                                     const PetscReal prog[])
{
  PetscFunctionBeginUser;
  if (w->kind == KERGS_WALL_FREE) {
    PetscCheck(nvals == 0, comm, PETSC_ERR_ARG_INCOMP, "Wall %s is free: -wall_%s_program applies to driven walls only", w->name, w->name);
    w->nprog = 0;
    if (vset)
      for (PetscInt d = 0; d < KERGS_DIM; d++) w->v[d] = vel[d];
    PetscFunctionReturn(0);
  }
  PetscCheck(!(vset && nvals), comm, PETSC_ERR_ARG_INCOMP, "Wall %s: give -wall_%s_velocity or -wall_%s_program, not both", w->name,
             w->name, w->name);
  if (vset) {
    w->nprog     = 1;
    w->prog_t[0] = 0.0;
    for (PetscInt d = 0; d < KERGS_DIM; d++) w->prog_v[0][d] = vel[d];
  }
  if (nvals) {
    const PetscInt width = 1 + KERGS_DIM; /* t, v */

    PetscCheck(nvals % width == 0, comm, PETSC_ERR_ARG_SIZ, "Wall %s: -wall_%s_program has %" PetscInt_FMT " values, not groups t,vx,vy",
               w->name, w->name, nvals);
    PetscCheck(nvals / width <= KERGS_MAX_PROGRAM, comm, PETSC_ERR_ARG_SIZ,
               "Wall %s: -wall_%s_program has %" PetscInt_FMT " pieces, at most %d", w->name, w->name, nvals / width, KERGS_MAX_PROGRAM);
    w->nprog = nvals / width;
    for (PetscInt k = 0; k < w->nprog; k++) {
      w->prog_t[k] = prog[width * k];
      for (PetscInt d = 0; d < KERGS_DIM; d++) w->prog_v[k][d] = prog[width * k + 1 + d];
      PetscCheck(k == 0 || w->prog_t[k] > w->prog_t[k - 1], comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "Wall %s: -wall_%s_program times must increase (piece %" PetscInt_FMT " starts at %g after %g)", w->name, w->name, k,
                 (double)w->prog_t[k], (double)w->prog_t[k - 1]);
    }
  }
  PetscFunctionReturn(0);
}

/* A guided wall moves along its normal only: neither its velocity nor its applied force may have a component along the
   wall (the contacts' impulses have none, by construction of H_f) beyond KERGS_GUIDE_TOL, relative: a force typed with
   6 significant digits on an oblique wall is accepted (GuideWall then takes it along n). On a restart the velocity is
   the checkpoint's. */
#define KERGS_GUIDE_TOL 1e-6
static PetscErrorCode CheckGuidedWall(MPI_Comm comm, const KergsWall *w)
{
  PetscReal t[KERGS_DIM], n[KERGS_DIM], vt = 0, ft = 0, vv = 0, ff = 0;

  PetscFunctionBeginUser;
  WallFrame(w, t, n);
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    vt += w->v[d] * t[d];
    ft += w->force[d] * t[d];
    vv += PetscSqr(w->v[d]);
    ff += PetscSqr(w->force[d]);
  }
  PetscCheck(PetscAbsReal(vt) <= KERGS_GUIDE_TOL * PetscSqrtReal(vv), comm, PETSC_ERR_ARG_INCOMP,
             "Wall %s is guided (it moves along its normal (%.10g, %.10g) only): its velocity (%.10g, %.10g) has a component %g of "
             "its size along the wall, above %g (-wall_%s_velocity; on a restart, the checkpoint's: a run whose wall was not guided "
             "continues with -wall_%s_guided false)",
             w->name, (double)(n[0] + 0.0), (double)(n[1] + 0.0), (double)w->v[0], (double)w->v[1], (double)(vt / PetscSqrtReal(vv)),
             (double)KERGS_GUIDE_TOL, w->name, w->name);
  PetscCheck(PetscAbsReal(ft) <= KERGS_GUIDE_TOL * PetscSqrtReal(ff), comm, PETSC_ERR_ARG_INCOMP,
             "Wall %s is guided (it moves along its normal (%.10g, %.10g) only): its force (%.10g, %.10g) has a component %g of its "
             "size along the wall, above %g (-wall_%s_force, or -wall_%s_guided false)",
             w->name, (double)(n[0] + 0.0), (double)(n[1] + 0.0), (double)w->force[0], (double)w->force[1],
             (double)(ft / PetscSqrtReal(ff)), (double)KERGS_GUIDE_TOL, w->name, w->name);
  PetscFunctionReturn(0);
}

/* A guided wall's given velocity and force, checked, then taken along n exactly (v <- (v.n) n, F <- (F.n) n). */
static PetscErrorCode GuideWall(MPI_Comm comm, KergsWall *w)
{
  PetscFunctionBeginUser;
  PetscCall(CheckGuidedWall(comm, w));
  KergsWallOnNormal(w, w->v);
  KergsWallOnNormal(w, w->force);
  PetscFunctionReturn(0);
}

/* -wall_<name>_pressure: a free wall's, finite and non-negative, instead of a constant -wall_<name>_force. */
static PetscErrorCode WallCheckPressureOptions(MPI_Comm comm, KergsWall *w, PetscBool force_set)
{
  PetscFunctionBeginUser;
  PetscCheck(w->kind == KERGS_WALL_FREE, comm, PETSC_ERR_ARG_INCOMP,
             "Wall %s is driven: -wall_%s_pressure applies to free walls only (-wall_%s_type free -wall_%s_mass m)", w->name, w->name,
             w->name, w->name);
  PetscCheck(KergsSceneFinite(w->pressure) && w->pressure >= 0.0, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Wall %s: -wall_%s_pressure %g must be finite and non-negative", w->name, w->name, (double)w->pressure);
  PetscCheck(!force_set, comm, PETSC_ERR_ARG_INCOMP,
             "Wall %s: give -wall_%s_pressure or -wall_%s_force, not both (the pressure sets the wall's force)", w->name, w->name, w->name);
  w->has_pressure = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* The options of one wall, prefix wall_<name>_. Declared walls must give both endpoints; box walls may
   override theirs. */
static PetscErrorCode WallSetFromOptions(KergsScene scene, KergsWall *w, PetscBool needs_endpoints, PetscReal time)
{
  char      prefix[KERGS_WALL_PREFIX_LEN], title[KERGS_WALL_PREFIX_LEN];
  PetscReal vel[KERGS_DIM] = {0}, *prog;
  PetscInt  nvals;
  PetscBool aset, bset, vset, fset, pset, gset;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(prefix, sizeof(prefix), "wall_%s_", w->name));
  PetscCall(PetscSNPrintf(title, sizeof(title), "Wall %s options", w->name));
  PetscOptionsBegin(scene->comm, prefix, title, NULL);
  PetscCall(
      KergsOptionsVector(PetscOptionsObject, "-a", "First endpoint x,y (the outward normal is the left normal of a->b)", w->a, &aset));
  PetscCall(KergsOptionsVector(PetscOptionsObject, "-b", "Second endpoint x,y", w->b, &bset));
  PetscCall(PetscOptionsEnum("-type", "Wall kind: driven (velocity program) or free (mass, applied force)", NULL, KergsWallKinds,
                             (PetscEnum)w->kind, (PetscEnum *)&w->kind, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-infinite", "Infinite line through a and b instead of the segment [a,b]", NULL,
                             w->infinite, &w->infinite, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-material", "Material index of the wall", NULL, w->material, &w->material, NULL));
  PetscCall(KergsOptionsVector(PetscOptionsObject, "-velocity",
                               "Constant velocity vx,vy of a driven wall, or initial velocity of a free wall", vel, &vset));
  PetscCall(KergsOptionsRealList(PetscOptionsObject, "-program",
                                 "Driven wall velocity program t0,vx,vy,t1,vx,vy,...: (vx,vy) from t_k to t_{k+1}, zero before t0", &nvals,
                                 &prog, NULL));
  PetscCall(PetscOptionsReal("-mass", "Mass of a free wall", NULL, w->mass, &w->mass, NULL));
  PetscCall(KergsOptionsVector(PetscOptionsObject, "-force", "Constant applied force fx,fy on a free wall", w->force, &fset));
  PetscCall(PetscOptionsReal("-pressure",
                             "Pressure (N/m) on a free wall: force = pressure x loaded length, along the normal, every step (the "
                             "separation of the two walls perpendicular to it, or its own length)",
                             NULL, w->pressure, &w->pressure, &pset));
  w->guided = pset;
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-guided",
                             "A free wall moves along its normal only, as the confining walls of a cell (default: true with -pressure, "
                             "false otherwise); false lets friction drag it along itself",
                             NULL, w->guided, &w->guided, &gset));
  PetscOptionsEnd();
  PetscCheck(!needs_endpoints || (aset && bset), scene->comm, PETSC_ERR_ARG_WRONGSTATE,
             "Wall %s (from -walls) needs both -wall_%s_a x,y and -wall_%s_b x,y", w->name, w->name, w->name);
  PetscCall(WallSetProgram(scene->comm, w, vel, vset, nvals, prog));
  if (w->kind == KERGS_WALL_DRIVEN) PetscCall(KergsWallVelocityAt(w, time, w->v));
  PetscCall(PetscFree(prog));
  if (pset) PetscCall(WallCheckPressureOptions(scene->comm, w, fset));
  if (w->kind == KERGS_WALL_FREE && w->guided) PetscCall(GuideWall(scene->comm, w));
  PetscCheck(!gset || !w->guided || w->kind == KERGS_WALL_FREE, scene->comm, PETSC_ERR_ARG_INCOMP,
             "Wall %s is driven: -wall_%s_guided applies to free walls only (-wall_%s_type free -wall_%s_mass m)", w->name, w->name,
             w->name, w->name);
  PetscFunctionReturn(0);
}

/* A wall name becomes part of option names: nonempty, unique, short enough for KergsWall.name. */
static PetscErrorCode WallCheckName(KergsScene scene, const KergsWall walls[], PetscInt nwalls, const char name[])
{
  size_t len;

  PetscFunctionBeginUser;
  PetscCall(PetscStrlen(name, &len));
  PetscCheck(len > 0, scene->comm, PETSC_ERR_ARG_WRONG, "-walls: empty wall name");
  PetscCheck(len < sizeof(walls[0].name), scene->comm, PETSC_ERR_ARG_WRONG, "-walls: wall name %s is longer than %d characters", name,
             (int)sizeof(walls[0].name) - 1);
  for (PetscInt w = 0; w < nwalls; w++) {
    PetscBool same;

    PetscCall(PetscStrcmp(walls[w].name, name, &same));
    PetscCheck(!same, scene->comm, PETSC_ERR_ARG_WRONG,
               "-walls: wall name %s is used twice (box walls are named box_bottom, box_right, box_top, box_left)", name);
  }
  PetscFunctionReturn(0);
}

/* Build the wall list: box walls, then declared walls, then every wall's own options. */
PetscErrorCode KergsSceneSetWalls(KergsScene scene, KergsWallsSpec *spec)
{
  PetscInt nbox = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscFree(scene->walls));
  scene->nwalls = 0;
  PetscCall(PetscCalloc1(4 + spec->nnames, &scene->walls));
  if (spec->box_from_sample) PetscCall(WallsBoxFromSample(scene->comm, spec, scene->restoring));
  if (spec->box_set) PetscCall(SceneBoxWalls(scene, spec->box, spec->open_top, &nbox, scene->walls));
  scene->nwalls = nbox;
  for (PetscInt k = 0; k < spec->nnames; k++) {
    PetscCall(WallCheckName(scene, scene->walls, scene->nwalls, spec->names[k]));
    PetscCall(PetscStrncpy(scene->walls[scene->nwalls].name, spec->names[k], sizeof(scene->walls[0].name)));
    scene->walls[scene->nwalls].kind = KERGS_WALL_DRIVEN;
    scene->nwalls++;
  }
  for (PetscInt w = 0; w < scene->nwalls; w++)
    PetscCall(WallSetFromOptions(scene, &scene->walls[w], w >= nbox ? PETSC_TRUE : PETSC_FALSE, scene->time));
  for (PetscInt w = 0; w < scene->nwalls; w++) WallSpan(scene->walls, scene->nwalls, w, scene->walls[w].span);
  UpdateWallPressures(scene);
  PetscCall(PetscStrNArrayDestroy(spec->nnames, &spec->names));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Validation and view                                                                              */

static PetscErrorCode CheckWall(KergsScene scene, const KergsWall *w)
{
  MPI_Comm  comm = scene->comm;
  PetscReal len2 = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    PetscCheck(KergsSceneFinite(w->a[d]) && KergsSceneFinite(w->b[d]), comm, PETSC_ERR_FP, "Wall %s: endpoint is not finite", w->name);
    PetscCheck(KergsSceneFinite(w->v[d]) && KergsSceneFinite(w->force[d]), comm, PETSC_ERR_FP, "Wall %s: velocity or force is not finite",
               w->name);
    len2 += (w->b[d] - w->a[d]) * (w->b[d] - w->a[d]);
  }
  PetscCheck(len2 > 0.0, comm, PETSC_ERR_ARG_WRONG, "Wall %s is degenerate: a == b = (%g, %g)", w->name, (double)w->a[0], (double)w->a[1]);
  PetscCheck(w->material >= 0 && w->material < scene->nmaterials, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Wall %s: material %" PetscInt_FMT " out of range [0, %" PetscInt_FMT ") (-wall_%s_material, -materials)", w->name,
             w->material, scene->nmaterials, w->name);
  PetscCheck(w->kind == KERGS_WALL_DRIVEN || w->kind == KERGS_WALL_FREE, comm, PETSC_ERR_ARG_OUTOFRANGE, "Wall %s: unknown kind %d",
             w->name, (int)w->kind);
  PetscCheck(w->kind != KERGS_WALL_FREE || (KergsSceneFinite(w->mass) && w->mass > 0.0), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Free wall %s: mass %g must be positive (-wall_%s_mass)", w->name, (double)w->mass, w->name);
  PetscCheck(!w->has_pressure || w->kind == KERGS_WALL_FREE, comm, PETSC_ERR_ARG_INCOMP,
             "Wall %s is driven: a pressure applies to free walls only (-wall_%s_type free)", w->name, w->name);
  PetscCheck(!w->has_pressure || (KergsSceneFinite(w->pressure) && w->pressure >= 0.0), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Wall %s: pressure %g must be finite and non-negative (-wall_%s_pressure)", w->name, (double)w->pressure, w->name);
  if (w->kind == KERGS_WALL_FREE && w->guided) PetscCall(CheckGuidedWall(comm, w));
  PetscCheck(w->nprog >= 0 && w->nprog <= KERGS_MAX_PROGRAM, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Wall %s: %" PetscInt_FMT " program pieces, at most %d", w->name, w->nprog, KERGS_MAX_PROGRAM);
  for (PetscInt k = 0; k < w->nprog; k++) {
    PetscCheck(KergsSceneFinite(w->prog_t[k]), comm, PETSC_ERR_FP, "Wall %s: program time %" PetscInt_FMT " is not finite", w->name, k);
    PetscCheck(k == 0 || w->prog_t[k] > w->prog_t[k - 1], comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Wall %s: program times must increase (piece %" PetscInt_FMT ")", w->name, k);
    for (PetscInt d = 0; d < KERGS_DIM; d++)
      PetscCheck(KergsSceneFinite(w->prog_v[k][d]), comm, PETSC_ERR_FP, "Wall %s: program velocity %" PetscInt_FMT " is not finite",
                 w->name, k);
  }
  PetscFunctionReturn(0);
}

/* Every fault of a wall named (-wall_<name>_... options). */
PetscErrorCode KergsSceneCheckWalls(KergsScene scene)
{
  PetscFunctionBeginUser;
  for (PetscInt w = 0; w < scene->nwalls; w++) PetscCall(CheckWall(scene, &scene->walls[w]));
  PetscFunctionReturn(0);
}

static PetscErrorCode ViewWall(PetscViewer viewer, const KergsWall walls[], const KergsWall *w)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, "wall %s: %s %s (%g, %g) -> (%g, %g), material %" PetscInt_FMT, w->name, KergsWallKinds[w->kind],
                                   w->infinite ? "line" : "segment", (double)w->a[0], (double)w->a[1], (double)w->b[0], (double)w->b[1],
                                   w->material));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
  if (w->kind == KERGS_WALL_FREE) {
    PetscCall(PetscViewerASCIIPrintf(viewer, ", mass %g, force (%g, %g), velocity (%g, %g)", (double)w->mass, (double)w->force[0],
                                     (double)w->force[1], (double)w->v[0], (double)w->v[1]));
    PetscCall(PetscViewerASCIIPrintf(viewer, w->guided ? ", guided along its normal" : ", free to slide along itself"));
    if (w->has_pressure && w->span[0] >= 0)
      PetscCall(PetscViewerASCIIPrintf(viewer, ", pressure %g over the length from %s to %s", (double)w->pressure, walls[w->span[0]].name,
                                       walls[w->span[1]].name));
    else if (w->has_pressure)
      PetscCall(PetscViewerASCIIPrintf(viewer, ", pressure %g over its own length", (double)w->pressure));
    PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
  } else if (w->nprog == 0) {
    PetscCall(PetscViewerASCIIPrintf(viewer, ", at rest\n"));
  } else {
    PetscCall(PetscViewerASCIIPrintf(viewer, ", velocity program"));
    for (PetscInt k = 0; k < w->nprog; k++)
      PetscCall(
          PetscViewerASCIIPrintf(viewer, " [t >= %g: (%g, %g)]", (double)w->prog_t[k], (double)w->prog_v[k][0], (double)w->prog_v[k][1]));
    PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
  }
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneViewWalls(KergsScene scene, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  for (PetscInt w = 0; w < scene->nwalls; w++) PetscCall(ViewWall(viewer, scene->walls, &scene->walls[w]));
  PetscFunctionReturn(0);
}
