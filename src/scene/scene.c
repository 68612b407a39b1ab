/* kergs scene: the container of the bodies, materials, loading programs and numerical settings, read from the options
   database, and the accessors through which the other components read them. The disks themselves come from
   src/scene/disks.c (list, lattice, random) and src/scene/sample_read.c (sample file); the walls, their options and
   motion from src/scene/walls.c; the distributed state from src/scene/ghosts.c. */
#include <kergs/private/sceneimpl.h>
#include <stdlib.h>
#include <petscviewer.h>

const char *const KergsGapRules[] = {"paper", "lmgc90", "predictive", "KergsGapRule", "KERGS_GAP_", NULL};

/* ------------------------------------------------------------------------------------------------ */
/* Create, destroy, disks                                                                          */

PetscErrorCode KergsSceneCreate(MPI_Comm comm, KergsScene *scene)
{
  KergsScene s;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(&s));
  s->comm = comm;
  PetscCall(PetscStrncpy(s->name, "unnamed", sizeof(s->name)));
  s->gravity[0] = 0.0;
  s->gravity[1] = -9.81;
  s->dt         = 1e-3;
  s->theta      = 1.0;
  s->nsteps     = 100;
  s->gaprule    = KERGS_GAP_PREDICTIVE; /* the paper's rule lets a pile at rest fall through its contacts (docs/solver.md) */
  s->alert      = -1.0;                 /* automatic: 0.1 * mean radius once the disks are known */
  s->ghost_skin = -1.0;                 /* automatic: the alert distance */
  s->nmaterials = 1;
  PetscCall(PetscMalloc1(1, &s->density));
  PetscCall(PetscCalloc1(1, &s->mu));
  s->density[0] = 1.0;
  *scene        = s;
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneFreeDisks(KergsScene scene)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(scene->id));
  PetscCall(PetscFree(scene->x));
  PetscCall(PetscFree(scene->rot));
  PetscCall(PetscFree(scene->v));
  PetscCall(PetscFree(scene->omega));
  PetscCall(PetscFree(scene->radius));
  PetscCall(PetscFree(scene->mass));
  PetscCall(PetscFree(scene->inertia));
  PetscCall(PetscFree(scene->material));
  PetscCall(PetscFree(scene->gidx));
  PetscCall(PetscFree(scene->xref));
  PetscCall(PetscFree(scene->ghost_owner));
  PetscCall(PetscSFDestroy(&scene->ghost_sf));
  scene->ndisks = scene->nowned = scene->nlocal = scene->nalloc = 0;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneDestroy(KergsScene *scene)
{
  PetscFunctionBeginUser;
  if (!*scene) PetscFunctionReturn(0);
  PetscCall(SceneFreeDisks(*scene));
  PetscCall(PetscFree((*scene)->walls));
  PetscCall(PetscFree((*scene)->density));
  PetscCall(PetscFree((*scene)->mu));
  PetscCall(PetscFree(*scene));
  PetscFunctionReturn(0);
}

/* Mass and inertia of a disk of radius r (2D: area pi r^2, I = m r^2 / 2 about its centre). */
static void DiskMass(PetscReal density, PetscReal r, PetscReal *mass, PetscReal *inertia)
{
  *mass    = density * PETSC_PI * r * r;
  *inertia = 0.5 * *mass * r * r;
}

/* Mass and inertia of each disk from its material's density. Disks with an invalid material are left massless:
   KergsSceneCheck reports them. */
static PetscErrorCode SceneComputeMasses(KergsScene scene)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < scene->nlocal; i++) {
    const PetscInt m = scene->material[i];

    DiskMass((m >= 0 && m < scene->nmaterials) ? scene->density[m] : 0.0, scene->radius[i], &scene->mass[i], &scene->inertia[i]);
  }
  PetscFunctionReturn(0);
}

/* Contiguous split of n disks over the ranks: [dstart, dend). */
static PetscErrorCode SceneSplitOwnership(KergsScene scene, PetscInt n)
{
  PetscInt nlocal = PETSC_DECIDE, end;

  PetscFunctionBeginUser;
  PetscCall(PetscSplitOwnership(scene->comm, &nlocal, &n));
  PetscCallMPI(MPI_Scan(&nlocal, &end, 1, MPIU_INT, MPI_SUM, scene->comm));
  scene->dstart = end - nlocal;
  scene->dend   = end;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneReserve(KergsScene scene, PetscInt n)
{
  PetscInt cap;

  PetscFunctionBeginUser;
  if (n <= scene->nalloc) PetscFunctionReturn(0);
  cap = PetscMax(n, scene->nalloc + scene->nalloc / 2);
  PetscCall(PetscRealloc(sizeof(PetscInt) * (size_t)cap, &scene->gidx));
  PetscCall(PetscRealloc(sizeof(PetscInt) * (size_t)cap, &scene->id));
  PetscCall(PetscRealloc(sizeof(PetscInt) * (size_t)cap, &scene->material));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap * KERGS_DIM, &scene->x));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap * KERGS_NROT, &scene->rot));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap * KERGS_DIM, &scene->v));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap * KERGS_NROT, &scene->omega));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap, &scene->radius));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap, &scene->mass));
  PetscCall(PetscRealloc(sizeof(PetscReal) * (size_t)cap, &scene->inertia));
  scene->nalloc = cap;
  PetscFunctionReturn(0);
}

/* frictional = some pair of materials that can actually meet has mu > 0. A pair (p, q) can meet when a disk of
   material p can touch a wall of material q, a disk of material q, or (p == q) another disk of material p. */
static PetscErrorCode SceneUpdateFrictional(KergsScene scene)
{
  const PetscInt nm = scene->nmaterials;
  PetscInt      *ndisk, *nwall;

  PetscFunctionBeginUser;
  scene->frictional = PETSC_FALSE;
  PetscCall(PetscCalloc2(nm, &ndisk, nm, &nwall));
  for (PetscInt i = 0; i < scene->nowned; i++)
    if (scene->material[i] >= 0 && scene->material[i] < nm) ndisk[scene->material[i]]++;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, ndisk, nm, MPIU_INT, MPI_SUM, scene->comm));
  for (PetscInt w = 0; w < scene->nwalls; w++)
    if (scene->walls[w].material >= 0 && scene->walls[w].material < nm) nwall[scene->walls[w].material]++;
  for (PetscInt p = 0; p < nm; p++) {
    for (PetscInt q = 0; q < nm; q++) {
      const PetscBool meet =
          (ndisk[p] > 0 && (nwall[q] > 0 || (p != q && ndisk[q] > 0) || (p == q && ndisk[p] > 1))) ? PETSC_TRUE : PETSC_FALSE;

      if (meet && scene->mu[p * nm + q] > 0.0) scene->frictional = PETSC_TRUE;
    }
  }
  PetscCall(PetscFree2(ndisk, nwall));
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneMeanRadius(KergsScene scene, PetscReal *mean)
{
  PetscReal sum = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < scene->nowned; i++) sum += scene->radius[i];
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, scene->comm));
  *mean = scene->ndisks ? sum / scene->ndisks : 0.0;
  PetscFunctionReturn(0);
}

/* The automatic alert distance (-alert not given), at its floor 0.1 * mean radius until KergsSceneAdaptAlert. */
static PetscErrorCode SceneSetAutomaticAlert(KergsScene scene)
{
  PetscReal mean;

  PetscFunctionBeginUser;
  PetscCall(SceneMeanRadius(scene, &mean));
  scene->alert = scene->alert_floor = 0.1 * mean;
  scene->alert_auto                 = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* (Re)place the disks: n disks at x (KERGS_DIM * n) with radii r (n); material (n) and v (KERGS_DIM * n) may
   be NULL (material 0, at rest). Ids are the indices, orientations and angular velocities zero, mass and
   inertia from the materials' densities. Collective: recomputes the ownership range [dstart, dend). */
PetscErrorCode KergsSceneSetDisks(KergsScene scene, PetscInt n, const PetscReal *x, const PetscReal *r, const PetscInt *material,
                                  const PetscReal *v)
{
  PetscFunctionBeginUser;
  PetscCheck(n >= 0, scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "KergsSceneSetDisks: negative number of disks %" PetscInt_FMT, n);
  PetscCheck(n == 0 || (x && r), scene->comm, PETSC_ERR_ARG_NULL, "KergsSceneSetDisks: positions and radii are required");
  for (PetscInt i = 0; material && i < n; i++)
    PetscCheck(material[i] >= 0 && material[i] < scene->nmaterials, scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Grain %" PetscInt_FMT " has material %" PetscInt_FMT ", out of range [0, %" PetscInt_FMT ") (see -materials)", i,
               material[i], scene->nmaterials);
  PetscCall(SceneFreeDisks(scene));
  PetscCall(SceneSplitOwnership(scene, n));
  scene->ndisks = n;
  scene->nowned = scene->nlocal = scene->dend - scene->dstart;
  PetscCall(KergsSceneReserve(scene, PetscMax(scene->nowned, 1)));
  for (PetscInt i = 0; i < scene->nowned; i++) {
    const PetscInt g = scene->dstart + i;

    scene->gidx[i] = scene->id[i] = g;
    scene->radius[i]              = r[g];
    scene->material[i]            = material ? material[g] : 0;
    for (PetscInt d = 0; d < KERGS_NROT; d++) scene->rot[KERGS_NROT * i + d] = scene->omega[KERGS_NROT * i + d] = 0.0;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      scene->x[KERGS_DIM * i + d] = x[KERGS_DIM * g + d];
      scene->v[KERGS_DIM * i + d] = v ? v[KERGS_DIM * g + d] : 0.0;
    }
  }
  PetscCall(SceneComputeMasses(scene));
  if ((scene->alert < 0.0 || scene->alert_auto) && n > 0) PetscCall(SceneSetAutomaticAlert(scene));
  PetscCall(SceneUpdateFrictional(scene));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneFriction(KergsScene scene, PetscInt mat_a, PetscInt mat_b, PetscReal *mu)
{
  PetscFunctionBeginUser;
  PetscCheck(mat_a >= 0 && mat_a < scene->nmaterials && mat_b >= 0 && mat_b < scene->nmaterials, scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Friction of materials (%" PetscInt_FMT ", %" PetscInt_FMT "): out of range [0, %" PetscInt_FMT ")", mat_a, mat_b,
             scene->nmaterials);
  *mu = scene->mu[mat_a * scene->nmaterials + mat_b];
  PetscFunctionReturn(0);
}

/* E_k = sum over disks of 1/2 m |v|^2 + 1/2 I omega^2; vmax = largest disk speed. */
PetscErrorCode KergsSceneKineticEnergy(KergsScene scene, PetscReal *ek, PetscReal *vmax)
{
  PetscReal e = 0.0, vm = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < scene->nowned; i++) {
    PetscReal v2 = 0.0, w2 = 0.0;

    for (PetscInt d = 0; d < KERGS_DIM; d++) v2 += scene->v[KERGS_DIM * i + d] * scene->v[KERGS_DIM * i + d];
    for (PetscInt d = 0; d < KERGS_NROT; d++) w2 += scene->omega[KERGS_NROT * i + d] * scene->omega[KERGS_NROT * i + d];
    e += 0.5 * scene->mass[i] * v2 + 0.5 * scene->inertia[i] * w2;
    vm = PetscMax(vm, PetscSqrtReal(v2));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &e, 1, MPIU_REAL, MPIU_SUM, scene->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &vm, 1, MPIU_REAL, MPIU_MAX, scene->comm));
  if (ek) *ek = e;
  if (vmax) *vmax = vm;
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Accessors                                                                                        */

PetscErrorCode KergsSceneGetDisks(KergsScene scene, KergsDisks *d)
{
  PetscFunctionBeginUser;
  d->ndisks      = scene->ndisks;
  d->nowned      = scene->nowned;
  d->nlocal      = scene->nlocal;
  d->dstart      = scene->dstart;
  d->dend        = scene->dend;
  d->gidx        = scene->gidx;
  d->id          = scene->id;
  d->material    = scene->material;
  d->ghost_owner = scene->ghost_owner;
  d->x           = scene->x;
  d->v           = scene->v;
  d->rot         = scene->rot;
  d->omega       = scene->omega;
  d->radius      = scene->radius;
  d->mass        = scene->mass;
  d->inertia     = scene->inertia;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetName(KergsScene scene, const char **name)
{
  PetscFunctionBeginUser;
  *name = scene->name;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetComm(KergsScene scene, MPI_Comm *comm)
{
  PetscFunctionBeginUser;
  *comm = scene->comm;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetTimeStep(KergsScene scene, PetscReal *dt, PetscReal *theta)
{
  PetscFunctionBeginUser;
  if (dt) *dt = scene->dt;
  if (theta) *theta = scene->theta;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetStep(KergsScene scene, PetscInt *step, PetscReal *time, PetscInt *nsteps)
{
  PetscFunctionBeginUser;
  if (step) *step = scene->step;
  if (time) *time = scene->time;
  if (nsteps) *nsteps = scene->nsteps;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetGravity(KergsScene scene, PetscReal gravity[])
{
  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < KERGS_DIM; d++) gravity[d] = scene->gravity[d];
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetMaterials(KergsScene scene, PetscInt *nmaterials, const PetscReal **mu)
{
  PetscFunctionBeginUser;
  if (nmaterials) *nmaterials = scene->nmaterials;
  if (mu) *mu = scene->mu;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetContactRule(KergsScene scene, PetscReal *alert, KergsGapRule *rule)
{
  PetscFunctionBeginUser;
  if (alert) *alert = scene->alert;
  if (rule) *rule = scene->gaprule;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetModel(KergsScene scene, PetscBool *frictional, PetscBool *rotating)
{
  PetscFunctionBeginUser;
  if (frictional) *frictional = scene->frictional;
  if (rotating) *rotating = (PetscBool)(scene->frictional && !scene->lock_rotation);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneSetRestoring(KergsScene scene, PetscBool restoring)
{
  PetscFunctionBeginUser;
  scene->restoring = restoring;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneRestoreDisks(KergsScene scene, PetscInt ndisks, PetscInt nowned, const PetscInt id[], const PetscInt material[],
                                      const PetscReal x[], const PetscReal rot[], const PetscReal v[], const PetscReal omega[],
                                      const PetscReal radius[])
{
  PetscInt end, total;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Scan(&nowned, &end, 1, MPIU_INT, MPI_SUM, scene->comm));
  PetscCall(MPIU_Allreduce(&nowned, &total, 1, MPIU_INT, MPI_SUM, scene->comm));
  PetscCheck(total == ndisks, scene->comm, PETSC_ERR_ARG_SIZ, "Scene %s: the ranks restore %" PetscInt_FMT " disks, not %" PetscInt_FMT,
             scene->name, total, ndisks);
  PetscCall(SceneFreeDisks(scene));
  scene->ndisks = ndisks;
  scene->dstart = end - nowned;
  scene->dend   = end;
  scene->nowned = scene->nlocal = nowned;
  PetscCall(KergsSceneReserve(scene, PetscMax(nowned, 1)));
  for (PetscInt i = 0; i < nowned; i++) {
    scene->gidx[i]     = scene->dstart + i;
    scene->id[i]       = id[i];
    scene->material[i] = material[i];
    scene->radius[i]   = radius[i];
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      scene->x[KERGS_DIM * i + d] = x[KERGS_DIM * i + d];
      scene->v[KERGS_DIM * i + d] = v[KERGS_DIM * i + d];
    }
    for (PetscInt d = 0; d < KERGS_NROT; d++) {
      scene->rot[KERGS_NROT * i + d]   = rot[KERGS_NROT * i + d];
      scene->omega[KERGS_NROT * i + d] = omega[KERGS_NROT * i + d];
    }
  }
  PetscCall(SceneComputeMasses(scene)); /* the formula of KergsSceneSetDisks: the same bits as the checkpointed run's */
  PetscCall(SceneUpdateFrictional(scene));
  PetscFunctionReturn(0);
}

/* The automatic alert distance (-alert not given): 0.1 * mean radius, or, when larger, twice the distance that two bodies
   approaching at `closing_speed` close in a step (the caller's bound: twice the fastest grain's speed, or the fastest grain
   and wall). A fixed alert missed contacts on a pile of radius ratio 100 (docs/running.md): grains falling at 4 m/s with
   dt 1e-3 close 8 mm in a step against an alert of 2.6 mm, and a contact met undetected sank 0.85 mm into a 0.6 mm
   grain; a quasi-static packing keeps the floor, and its trajectory is unchanged. A given -alert is kept as it is. */
PetscErrorCode KergsSceneAdaptAlert(KergsScene scene, PetscReal closing_speed)
{
  PetscFunctionBeginUser;
  /* at most 20 times the floor, twice the mean radius: a grain that crosses its own size in a step is past what the step
     resolves (the watch stops such a run by default), and with the watch off a blown-up crystal of 96 grains at 334 m/s
     otherwise made every pair potential (tests/test_regularised.c: 200 s instead of 1 s) */
  if (scene->alert_auto) scene->alert = PetscMin(20.0 * scene->alert_floor, PetscMax(scene->alert_floor, 2.0 * closing_speed * scene->dt));
  PetscFunctionReturn(0);
}

static int CompareGrainIndex(const void *x, const void *y)
{
  const KergsGrainIndex *p = (const KergsGrainIndex *)x, *q = (const KergsGrainIndex *)y;
  return p->id < q->id ? -1 : (p->id > q->id ? 1 : 0);
}

PetscErrorCode KergsSceneGetGrainIndex(KergsScene scene, PetscInt n, KergsGrainIndex **table)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(n + 1, table));
  for (PetscInt i = 0; i < n; i++) (*table)[i] = (KergsGrainIndex){scene->id[i], i};
  qsort(*table, (size_t)n, sizeof(KergsGrainIndex), CompareGrainIndex);
  PetscFunctionReturn(0);
}

PetscInt KergsGrainIndexFind(const KergsGrainIndex table[], PetscInt n, PetscInt id)
{
  const KergsGrainIndex key = {id, -1}, *hit = (const KergsGrainIndex *)bsearch(&key, table, (size_t)n, sizeof(key), CompareGrainIndex);

  return hit ? hit->local : -1;
}

/* Whether the alert distance is automatic, and its floor then. */
PetscErrorCode KergsSceneGetAlertFloor(KergsScene scene, PetscBool *automatic, PetscReal *floor)
{
  PetscFunctionBeginUser;
  if (automatic) *automatic = scene->alert_auto;
  if (floor) *floor = scene->alert_floor;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneRestoreState(KergsScene scene, PetscInt step, PetscReal time, PetscReal alert, PetscReal alert_floor)
{
  PetscFunctionBeginUser;
  scene->step = step;
  scene->time = time;
  if (scene->alert_auto) { /* the disks' options were not read: no mean radius of their own */
    scene->alert       = alert;
    scene->alert_floor = alert_floor;
  } /* else the -alert of this run's options: the checkpointed run's, or the command line's */
  PetscFunctionReturn(0);
}

/* x+ = x- + dt (theta V+ + (1 - theta) V-) for the owned disks, then the walls (KergsSceneAdvanceWalls), then the
   clock. */
PetscErrorCode KergsSceneAdvance(KergsScene sc, const PetscReal vold[], const PetscReal wold[], const PetscReal wvold[])
{
  const PetscReal th = sc->theta, dt = sc->dt;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < KERGS_DIM * sc->nowned; i++) sc->x[i] += dt * (th * sc->v[i] + (1 - th) * vold[i]);
  for (PetscInt i = 0; i < KERGS_NROT * sc->nowned; i++) sc->rot[i] += dt * (th * sc->omega[i] + (1 - th) * wold[i]);
  PetscCall(KergsSceneAdvanceWalls(sc, wvold));
  sc->time += sc->dt;
  sc->step++;
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Options: numerics, materials                                                                    */

/* Whether -alert was given as the word "default" (PETSc reads it as PETSC_DEFAULT), which brings back the automatic
   alert over an options file's value. The string is checked, so that a negative number typed by mistake is still
   refused by SceneCheckNumerics. */
static PetscErrorCode AlertGivenAsDefault(PetscBool *automatic)
{
  char      value[32] = "";
  PetscBool set, word, petsc_word;

  PetscFunctionBeginUser;
  *automatic = PETSC_FALSE;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-alert", value, sizeof(value), &set));
  if (!set) PetscFunctionReturn(0);
  PetscCall(PetscStrcasecmp(value, "default", &word));
  PetscCall(PetscStrcasecmp(value, "petsc_default", &petsc_word));
  *automatic = (PetscBool)(word || petsc_word);
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneNumericsOptions(PetscOptionItems *PetscOptionsObject, KergsScene scene, PetscBool *alert_set)
{
  PetscFunctionBeginUser;
  PetscCall(
      PetscOptionsString("-scene_name", "Name of the scene (used in output)", NULL, scene->name, scene->name, sizeof(scene->name), NULL));
  PetscCall(PetscOptionsName("-scene_view", "Print the scene (disks, walls, materials) at the start of the run (PETSc viewer syntax)",
                             "KergsSceneView", NULL));
  PetscCall(KergsOptionsVector(PetscOptionsObject, "-gravity", "Gravity acceleration gx,gy (m/s^2)", scene->gravity, NULL));
  PetscCall(PetscOptionsReal("-dt", "Time step (s)", NULL, scene->dt, &scene->dt, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-steps", "Number of time steps", NULL, scene->nsteps, &scene->nsteps, NULL));
  PetscCall(PetscOptionsReal("-theta", "Theta of the theta-method, in (0,1] (Algorithm 1)", NULL, scene->theta, &scene->theta, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-disks_lock_rotation",
                             "Disks translate only: no rotational DOFs even with friction (sliding blocks)", NULL, scene->lock_rotation,
                             &scene->lock_rotation, NULL));
  PetscCall(PetscOptionsEnum(
      "-gap_rule",
      "Active contacts: paper (g~ = g- <= 0), lmgc90 (g~ = g- + (1-theta) dt vn- <= 0), predictive (every contact within the "
      "alert distance, v_n >= -max(g~, 0) / (theta dt): may close during the step, never further; the default)",
      NULL, KergsGapRules, (PetscEnum)scene->gaprule, (PetscEnum *)&scene->gaprule, NULL));
  PetscCall(PetscOptionsReal(
      "-alert",
      "Alert distance >= 0: potential contacts have gap < alert (default, or the word default: 0.1 * mean radius, raised at each step "
      "to twice the distance the fastest pair closes in a step, at most twice the mean radius, KergsSceneAdaptAlert)",
      NULL, scene->alert, &scene->alert, alert_set));
  if (*alert_set) {
    PetscBool automatic;

    PetscCall(AlertGivenAsDefault(&automatic));
    if (automatic) *alert_set = PETSC_FALSE;
  }
  PetscCall(PetscOptionsReal("-ghost_skin",
                             "Skin of the ghost layer: ghosts are rebuilt once the alert distance plus twice a disk's displacement "
                             "exceeds the build's alert plus skin (negative: the alert distance)",
                             "KergsSceneUpdateGhosts", scene->ghost_skin, &scene->ghost_skin, NULL));
  PetscFunctionReturn(0);
}

/* -materials, -material_density, -friction, -friction_pairs. */
static PetscErrorCode SceneMaterialOptions(PetscOptionItems *PetscOptionsObject, KergsScene scene)
{
  PetscInt   nm     = scene->nmaterials, nd, np;
  PetscReal  mu_all = 0.0, *dens, *pairs;
  PetscBool  set, mu_set;
  const char pre[] = "Scene materials";

  PetscFunctionBeginUser;
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-materials", "Number of materials", NULL, nm, &nm, &set));
  PetscCheck(nm >= 1, PetscOptionsObject->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s: -materials %" PetscInt_FMT " must be at least 1", pre, nm);
  PetscCall(KergsOptionsRealList(PetscOptionsObject, "-material_density",
                                 "Density of each material, d0,d1,... (mass per unit area, default 1)", &nd, &dens, NULL));
  PetscCall(PetscOptionsReal("-friction", "Friction coefficient of every pair of materials", NULL, mu_all, &mu_all, &mu_set));
  PetscCall(KergsOptionsRealList(PetscOptionsObject, "-friction_pairs",
                                 "Friction of given pairs i,j,mu,i,j,mu,... (overrides -friction, symmetric)", &np, &pairs, NULL));
  PetscCheck(nd == 0 || nd == 1 || nd == nm, PetscOptionsObject->comm, PETSC_ERR_ARG_SIZ,
             "%s: -material_density has %" PetscInt_FMT " values; give 1 or -materials = %" PetscInt_FMT, pre, nd, nm);
  PetscCheck(np % 3 == 0, PetscOptionsObject->comm, PETSC_ERR_ARG_SIZ,
             "%s: -friction_pairs has %" PetscInt_FMT " values, not triples i,j,mu", pre, np);
  if (set || nm != scene->nmaterials) { /* new material table: densities 1, no friction */
    PetscCall(PetscFree(scene->density));
    PetscCall(PetscFree(scene->mu));
    scene->nmaterials = nm;
    PetscCall(PetscMalloc1(nm, &scene->density));
    PetscCall(PetscCalloc1(nm * nm, &scene->mu));
    for (PetscInt m = 0; m < nm; m++) scene->density[m] = 1.0;
  }
  for (PetscInt m = 0; m < nm && nd; m++) scene->density[m] = dens[nd == 1 ? 0 : m];
  for (PetscInt k = 0; k < nm * nm && mu_set; k++) scene->mu[k] = mu_all;
  for (PetscInt k = 0; k < np; k += 3) {
    const PetscInt i = (PetscInt)pairs[k], j = (PetscInt)pairs[k + 1];

    PetscCheck(pairs[k] == (PetscReal)i && pairs[k + 1] == (PetscReal)j && i >= 0 && i < nm && j >= 0 && j < nm, PetscOptionsObject->comm,
               PETSC_ERR_ARG_OUTOFRANGE,
               "%s: -friction_pairs triple %" PetscInt_FMT " names materials (%g, %g), not integers in [0, %" PetscInt_FMT ")", pre, k / 3,
               (double)pairs[k], (double)pairs[k + 1], nm);
    scene->mu[i * nm + j] = scene->mu[j * nm + i] = pairs[k + 2];
  }
  PetscCall(PetscFree(dens));
  PetscCall(PetscFree(pairs));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */

/* Read the scene from the options database: numerics, materials, walls, disks; then check it. */
PetscErrorCode KergsSceneSetFromOptions(KergsScene scene)
{
  KergsWallsSpec walls;
  PetscReal      alert;
  PetscBool      alert_set = PETSC_FALSE, help;

  PetscFunctionBeginUser;
  PetscOptionsBegin(scene->comm, NULL, "Scene options", NULL);
  PetscCall(SceneNumericsOptions(PetscOptionsObject, scene, &alert_set));
  PetscCall(SceneMaterialOptions(PetscOptionsObject, scene));
  PetscCall(KergsSceneWallsOptions(PetscOptionsObject, &walls));
  PetscOptionsEnd();
  PetscCall(KergsSceneSetWalls(scene, &walls));

  alert = scene->alert;
  PetscCall(KergsSceneDisksSetFromOptions(scene));
  PetscCall(SceneComputeMasses(scene)); /* the densities may have changed since the disks were set */
  if (walls.affine_start && !scene->restoring) PetscCall(KergsSceneBoxAffineStart(scene));
  if (alert_set) {
    scene->alert      = alert; /* the user's value, even a negative one (then rejected) */
    scene->alert_auto = PETSC_FALSE;
  } else
    PetscCall(SceneSetAutomaticAlert(scene));
  PetscCall(SceneUpdateFrictional(scene));
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  /* -help alone lists the options of an empty scene; a restored scene is checked once its state is in place */
  if (!help && !scene->restoring) PetscCall(KergsSceneCheck(scene));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Validation                                                                                       */

static PetscErrorCode SceneCheckNumerics(KergsScene scene)
{
  MPI_Comm comm = scene->comm;

  PetscFunctionBeginUser;
  PetscCheck(KergsSceneFinite(scene->dt) && scene->dt > 0.0, comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: time step -dt %g must be positive",
             scene->name, (double)scene->dt);
  PetscCheck(KergsSceneFinite(scene->theta) && scene->theta > 0.0 && scene->theta <= 1.0, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene %s: -theta %g must be in (0,1]", scene->name, (double)scene->theta);
  PetscCheck(scene->nsteps >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: -steps %" PetscInt_FMT " must be >= 0", scene->name,
             scene->nsteps);
  PetscCheck(KergsSceneFinite(scene->alert) && scene->alert >= 0.0, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene %s: alert distance -alert %g must be >= 0", scene->name, (double)scene->alert);
  PetscCheck(KergsSceneFinite(scene->ghost_skin), comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: -ghost_skin %g is not finite", scene->name,
             (double)scene->ghost_skin);
  PetscCheck(scene->gaprule == KERGS_GAP_PAPER || scene->gaprule == KERGS_GAP_LMGC90 || scene->gaprule == KERGS_GAP_PREDICTIVE, comm,
             PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: unknown gap rule %d", scene->name, (int)scene->gaprule);
  for (PetscInt d = 0; d < KERGS_DIM; d++)
    PetscCheck(KergsSceneFinite(scene->gravity[d]), comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: -gravity is not finite", scene->name);
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneCheckMaterials(KergsScene scene)
{
  const PetscInt nm   = scene->nmaterials;
  MPI_Comm       comm = scene->comm;

  PetscFunctionBeginUser;
  PetscCheck(nm >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: -materials %" PetscInt_FMT " must be at least 1", scene->name, nm);
  for (PetscInt m = 0; m < nm; m++)
    PetscCheck(KergsSceneFinite(scene->density[m]) && scene->density[m] > 0.0, comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Scene %s: density of material %" PetscInt_FMT " is %g, must be positive (-material_density)", scene->name, m,
               (double)scene->density[m]);
  for (PetscInt p = 0; p < nm; p++) {
    for (PetscInt q = 0; q < nm; q++) {
      const PetscReal mu = scene->mu[p * nm + q];

      PetscCheck(KergsSceneFinite(mu) && mu >= 0.0, comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "Scene %s: friction coefficient of materials (%" PetscInt_FMT ", %" PetscInt_FMT
                 ") is %g, must be finite and >= 0 (-friction, -friction_pairs)",
                 scene->name, p, q, (double)mu);
      PetscCheck(mu == scene->mu[q * nm + p], comm, PETSC_ERR_ARG_WRONG,
                 "Scene %s: friction of materials (%" PetscInt_FMT ", %" PetscInt_FMT ") is not symmetric", scene->name, p, q);
    }
  }
  PetscFunctionReturn(0);
}

/* One disk's state, as the checks read it. */
typedef struct {
  PetscInt  id, material;
  PetscReal x[KERGS_DIM], v[KERGS_DIM], rot[KERGS_NROT], omega[KERGS_NROT], radius;
} DiskCheckRecord;

static void GetDiskCheckRecord(KergsScene scene, PetscInt i, DiskCheckRecord *d)
{
  d->id       = scene->id ? scene->id[i] : i;
  d->material = scene->material[i];
  d->radius   = scene->radius[i];
  for (PetscInt k = 0; k < KERGS_DIM; k++) {
    d->x[k] = scene->x[KERGS_DIM * i + k];
    d->v[k] = scene->v[KERGS_DIM * i + k];
  }
  for (PetscInt k = 0; k < KERGS_NROT; k++) {
    d->rot[k]   = scene->rot[KERGS_NROT * i + k];
    d->omega[k] = scene->omega[KERGS_NROT * i + k];
  }
}

/* Every fault of one disk, named by grain id; comm is the communicator that errors. */
static PetscErrorCode CheckDisk(MPI_Comm comm, PetscInt nmaterials, const PetscReal density[], const DiskCheckRecord *d)
{
  PetscFunctionBeginUser;
  PetscCheck(KergsSceneFinite(d->radius) && d->radius > 0.0, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Grain %" PetscInt_FMT ": radius %g must be positive and finite", d->id, (double)d->radius);
  for (PetscInt k = 0; k < KERGS_DIM; k++) {
    PetscCheck(KergsSceneFinite(d->x[k]), comm, PETSC_ERR_FP, "Grain %" PetscInt_FMT ": position component %" PetscInt_FMT " is %g", d->id,
               k, (double)d->x[k]);
    PetscCheck(KergsSceneFinite(d->v[k]), comm, PETSC_ERR_FP, "Grain %" PetscInt_FMT ": velocity component %" PetscInt_FMT " is %g", d->id,
               k, (double)d->v[k]);
  }
  for (PetscInt k = 0; k < KERGS_NROT; k++) {
    PetscCheck(KergsSceneFinite(d->rot[k]), comm, PETSC_ERR_FP, "Grain %" PetscInt_FMT ": orientation is %g", d->id, (double)d->rot[k]);
    PetscCheck(KergsSceneFinite(d->omega[k]), comm, PETSC_ERR_FP, "Grain %" PetscInt_FMT ": angular velocity is %g", d->id,
               (double)d->omega[k]);
  }
  PetscCheck(d->material >= 0 && d->material < nmaterials, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Grain %" PetscInt_FMT ": material %" PetscInt_FMT " out of range [0, %" PetscInt_FMT ") (see -materials)", d->id, d->material,
             nmaterials);
  {
    /* M^-1 enters every step: a mass or a moment of inertia that underflows to 0 or overflows makes the first update
       non-finite, which the watch then reports as a blow-up that names no cause */
    PetscReal mass, inertia;
    DiskMass(density[d->material], d->radius, &mass, &inertia);
    PetscCheck(PetscIsNormalReal(mass) && PetscIsNormalReal(inertia) && PetscIsNormalReal(1.0 / inertia), comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Grain %" PetscInt_FMT ": radius %g and density %g (material %" PetscInt_FMT ") give a mass %g and a moment of inertia %g "
               "that double precision cannot invert",
               d->id, (double)d->radius, (double)density[d->material], d->material, (double)mass, (double)inertia);
  }
  PetscFunctionReturn(0);
}

/* Collective: the owned disks are checked where they live; the faulty disk of lowest global index is then
   broadcast from its owner so that every rank raises the same error (no rank is left waiting). */
static PetscErrorCode SceneCheckDisks(KergsScene scene)
{
  DiskCheckRecord d;
  PetscInt        bad = PETSC_MAX_INT, gbad;
  PetscMPIInt     rank, owner = -1;

  PetscFunctionBeginUser;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL)); /* quiet: the message comes below, on every rank */
  for (PetscInt i = 0; i < scene->nowned && bad == PETSC_MAX_INT; i++) {
    GetDiskCheckRecord(scene, i, &d);
    if (CheckDisk(PETSC_COMM_SELF, scene->nmaterials, scene->density, &d) != 0) bad = scene->dstart + i;
  }
  PetscCall(PetscPopErrorHandler());
  PetscCall(MPIU_Allreduce(&bad, &gbad, 1, MPIU_INT, MPI_MIN, scene->comm));
  if (gbad == PETSC_MAX_INT) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_rank(scene->comm, &rank));
  if (gbad >= scene->dstart && gbad < scene->dend) {
    owner = rank;
    GetDiskCheckRecord(scene, gbad - scene->dstart, &d);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &owner, 1, MPI_INT, MPI_MAX, scene->comm));
  PetscCallMPI(MPI_Bcast(&d, (PetscMPIInt)sizeof(d), MPI_BYTE, owner, scene->comm));
  PetscCall(CheckDisk(scene->comm, scene->nmaterials, scene->density, &d));
  PetscFunctionReturn(0);
}

/* Every fault of the input named; overlaps of grains are left to the contact detection. */
PetscErrorCode KergsSceneCheck(KergsScene scene)
{
  PetscFunctionBeginUser;
  PetscCheck(scene->ndisks > 0 || scene->nwalls > 0, scene->comm, PETSC_ERR_ARG_WRONGSTATE,
             "Scene %s has no disks and no walls (give -disks_source and its options, -box or -walls)", scene->name);
  PetscCall(SceneCheckMaterials(scene)); /* first: the disks' check reads the densities */
  PetscCall(SceneCheckDisks(scene));
  PetscCall(SceneCheckNumerics(scene));
  PetscCall(KergsSceneCheckWalls(scene));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* View                                                                                             */

static PetscErrorCode SceneViewMaterials(KergsScene scene, PetscViewer viewer)
{
  const PetscInt nm = scene->nmaterials;

  PetscFunctionBeginUser;
  for (PetscInt m = 0; m < nm; m++) {
    PetscCall(PetscViewerASCIIPrintf(viewer, "material %" PetscInt_FMT ": density %g, friction with materials 0..%" PetscInt_FMT ":", m,
                                     (double)scene->density[m], nm - 1));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
    for (PetscInt q = 0; q < nm; q++) PetscCall(PetscViewerASCIIPrintf(viewer, " %g", (double)scene->mu[m * nm + q]));
    PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneViewAdapter(void *scene, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneView((KergsScene)scene, viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneViewFromOptions(KergsScene scene, const char name[])
{
  PetscFunctionBeginUser;
  PetscCall(KergsViewFromOptions(scene->comm, NULL, name, SceneViewAdapter, scene));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneView(KergsScene scene, PetscViewer viewer)
{
  PetscBool iascii;
  PetscReal rmin = PETSC_MAX_REAL, rmax = 0.0;

  PetscFunctionBeginUser;
  if (!viewer) viewer = PETSC_VIEWER_STDOUT_(scene->comm);
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &iascii));
  if (!iascii) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < scene->nowned; i++) {
    rmin = PetscMin(rmin, scene->radius[i]);
    rmax = PetscMax(rmax, scene->radius[i]);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rmin, 1, MPIU_REAL, MPIU_MIN, scene->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rmax, 1, MPIU_REAL, MPIU_MAX, scene->comm));
  if (!scene->ndisks) rmin = 0.0;
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "Scene %s: %" PetscInt_FMT " disks (radius %g to %g), %" PetscInt_FMT " walls, %" PetscInt_FMT " materials\n", scene->name,
      scene->ndisks, (double)rmin, (double)rmax, scene->nwalls, scene->nmaterials));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "dt %g, steps %" PetscInt_FMT ", theta %g, gap rule %s, alert distance %g, gravity (%g, %g)\n",
                                   (double)scene->dt, scene->nsteps, (double)scene->theta, KergsGapRules[scene->gaprule],
                                   (double)scene->alert, (double)scene->gravity[0], (double)scene->gravity[1]));
  PetscCall(PetscViewerASCIIPrintf(viewer, "%s\n",
                                   scene->frictional ? (scene->lock_rotation ? "frictional (tangential impulses), rotations locked"
                                                                             : "frictional (tangential impulses, rotations)")
                                                     : "frictionless (normal impulses only)"));
  PetscCall(SceneViewMaterials(scene, viewer));
  PetscCall(KergsSceneViewWalls(scene, viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}
