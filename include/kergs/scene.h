/* kergs scene: the bodies (disks, walls), materials, loading programs and numerical settings of a run.
   A scene is read from the options database (an options file under cases/); its disks come from a
   built-in generator (lattice, random) or from a sample file written by an earlier run.
   The disk state is distributed (docs/design.md, "Parallel layout"): rank p owns the disks of the global index range
   [dstart, dend), stored first in its local arrays, followed by ghost copies of other ranks' disks that can
   touch its own (src/scene/ghosts.c). A disk's global index is its place in the current partition's numbering
   (it changes when disks migrate); its grain id is persistent. */
#ifndef KERGS_SCENE_H
#define KERGS_SCENE_H

#include <kergs/base.h>
#include <petscsf.h>

typedef enum {
  KERGS_WALL_DRIVEN, /* velocity given by a program: its DOFs are in V_g */
  KERGS_WALL_FREE    /* a body with mass and applied force: its DOFs are in V_f */
} KergsWallKind;
PETSC_EXTERN const char *const KergsWallKinds[];

typedef enum {
  KERGS_GAP_PAPER,     /* predicted gap g~ = g^- (Alart 2013) */
  KERGS_GAP_LMGC90,    /* g~ = g^- + (1 - theta) dt v_n^- (LMGC90) */
  KERGS_GAP_PREDICTIVE /* every contact within the alert distance, Signorini on the end-of-step gap: v_n >= -g~+ / (theta dt) */
} KergsGapRule;
PETSC_EXTERN const char *const KergsGapRules[];

#define KERGS_MAX_PROGRAM 16 /* pieces of a wall's velocity program */

/* A wall is a one-sided line or segment from a to b; its outward normal is the left normal of a->b,
   n = (-(b-a)_y, (b-a)_x) / |b-a|, and only disks on that side touch it. Walls translate, never rotate. */
typedef struct {
  char          name[64];
  KergsWallKind kind;
  PetscBool     infinite;                   /* a line (PETSC_TRUE) or the segment [a, b] */
  PetscReal     a[KERGS_DIM], b[KERGS_DIM]; /* current endpoints */
  PetscInt      material;
  /* driven wall: piecewise-constant velocity, piece k holds from prog_t[k] to prog_t[k+1] */
  PetscInt  nprog;
  PetscReal prog_t[KERGS_MAX_PROGRAM];
  PetscReal prog_v[KERGS_MAX_PROGRAM][KERGS_DIM];
  /* free wall: translational mass and applied force; a guided one moves along its normal only (its velocity and
     force have no component along the wall, and the contacts push it along n only: H_f sees n n^T of its DOFs) */
  PetscReal mass, force[KERGS_DIM];
  PetscBool guided;
  /* pressure-controlled free wall: force = pressure x loaded length along n, set again after every move of the walls.
     The loaded length is the separation of the two walls perpendicular to this one that face each other across it,
     span[0] facing along a->b and span[1] against it; without exactly one of each (span -1), the wall's own |b - a|. */
  PetscBool has_pressure;
  PetscReal pressure;
  PetscInt  span[2];
  PetscReal v[KERGS_DIM];    /* current velocity */
  PetscReal disp[KERGS_DIM]; /* displacement since the start of the run */
} KergsWall;

typedef struct _p_KergsScene *KergsScene;

/* This rank's disks (KergsSceneGetDisks): a structure of arrays, owned disks [0, nowned) first, then ghosts
   [nowned, nlocal). The arrays are the scene's own, valid until the disks are replaced (KergsSceneSetDisks), migrate
   (KergsSceneMigrate) or the ghost layer is rebuilt (KergsSceneUpdateGhosts); only the time step's update writes the
   owned disks' positions and velocities (KergsSceneAdvance). */
typedef struct {
  PetscInt         ndisks;         /* global number of disks */
  PetscInt         nowned, nlocal; /* disks owned here; owned + ghosts */
  PetscInt         dstart, dend;   /* global indices of the owned disks */
  const PetscInt  *gidx;           /* global index (owned disk i: dstart + i) */
  const PetscInt  *id;             /* persistent grain id */
  const PetscInt  *material;
  const PetscInt  *ghost_owner; /* per ghost (local index nowned + g): the rank that owns it */
  PetscReal       *x, *v;       /* KERGS_DIM per disk: centre, velocity */
  PetscReal       *rot, *omega; /* KERGS_NROT per disk: orientation, angular velocity */
  const PetscReal *radius, *mass, *inertia;
} KergsDisks;

/* Defaults: gravity (0, -9.81), dt 1e-3, 100 steps, theta 1, paper gap rule, one material of density 1 without
   friction, alert automatic (negative until disks are set), no disks, no walls. */
PETSC_EXTERN PetscErrorCode KergsSceneCreate(MPI_Comm, KergsScene *);
/* Reads every scene option (run with -help for the list), generates the disks, then calls KergsSceneCheck. */
PETSC_EXTERN PetscErrorCode KergsSceneSetFromOptions(KergsScene);
/* Collective. Replaces the disks by the n disks given, the same arrays on every rank: x (KERGS_DIM * n), r (n);
   material and v may be NULL (material 0, at rest). Each rank keeps its slice of the even contiguous split as its
   owned disks (no ghosts yet). Sets id = global index, rot = omega = 0, mass and inertia from the densities,
   recomputes frictional, and sets alert = 0.1 * mean radius if alert is still automatic (negative). */
PETSC_EXTERN PetscErrorCode KergsSceneSetDisks(KergsScene, PetscInt n, const PetscReal *x, const PetscReal *r, const PetscInt *material,
                                               const PetscReal *v);
/* Errors naming the grain, wall, material pair or option at fault; overlaps are not checked here. */
PETSC_EXTERN PetscErrorCode KergsSceneCheck(KergsScene);
PETSC_EXTERN PetscErrorCode KergsSceneView(KergsScene, PetscViewer);
/* name given (-scene_view [viewer]): view the scene there. Collective. */
PETSC_EXTERN PetscErrorCode KergsSceneViewFromOptions(KergsScene, const char name[]);
PETSC_EXTERN PetscErrorCode KergsSceneDestroy(KergsScene *);
PETSC_EXTERN PetscErrorCode KergsSceneFriction(KergsScene, PetscInt mat_a, PetscInt mat_b, PetscReal *mu);
/* Driven wall: its program's velocity at time t (zero before the first piece or without program).
   Free wall: its current velocity wall->v. */
PETSC_EXTERN PetscErrorCode KergsWallVelocityAt(const KergsWall *, PetscReal t, PetscReal v[]);
/* The wall's unit normal n, towards the disks' side (the left normal of a->b). */
PETSC_EXTERN void KergsWallNormal(const KergsWall *, PetscReal n[]);
/* v <- (v.n) n: a guided wall's velocity or force taken along its normal. */
PETSC_EXTERN void KergsWallOnNormal(const KergsWall *, PetscReal v[]);
/* Collective, over all disks: ek = sum 1/2 m |v|^2 + 1/2 I omega^2, vmax = largest speed. */
PETSC_EXTERN PetscErrorCode KergsSceneKineticEnergy(KergsScene, PetscReal *ek, PetscReal *vmax);
/* Make room for n local disks (owned + ghosts), keeping the first nlocal. */
PETSC_EXTERN PetscErrorCode KergsSceneReserve(KergsScene, PetscInt n);

/* Disk source "file": replace the scene's disks with those of a sample file written by KergsSampleWrite (kergs/sample.h;
   materials must exist in the scene, grain ids must be distinct non-negative integers). The scene's time is set to 0:
   the file's time is the run's that wrote it, and a run from a sample keeps its own clock. Collective. */
PETSC_EXTERN PetscErrorCode KergsSampleRead(KergsScene, const char path[]);
/* The box x0,y0,x1,y1 a sample file records (its run's four box walls where they stood), for -box_from_sample. */
PETSC_EXTERN PetscErrorCode KergsSampleReadBox(MPI_Comm, const char path[], PetscReal box[4]);
/* For readers that name grains by id (checkpoints, samples): the ids of the first n local disks (owned first, then
   ghosts) with their local indices, sorted by id (PetscFree), and the local index of an id in it, or -1. */
typedef struct {
  PetscInt id, local;
} KergsGrainIndex;
PETSC_EXTERN PetscErrorCode KergsSceneGetGrainIndex(KergsScene, PetscInt n, KergsGrainIndex **table);
PETSC_EXTERN PetscInt       KergsGrainIndexFind(const KergsGrainIndex table[], PetscInt n, PetscInt id);
/* The walls' names joined by commas, in wall order (PetscFree): how files record which walls a run had. */
PETSC_EXTERN PetscErrorCode KergsSceneGetWallNames(KergsScene, char **joined);
/* The disk source -disks_source names ("list" when it is not given), read outside the disks' options block: for the
   options that only one source uses (-box_from_sample, -sample_forces). */
PETSC_EXTERN PetscErrorCode KergsSceneDisksSourceFromOptions(char source[], size_t len);
/* The sample file the disks were read from by KergsSampleRead; an empty string when they were not. */
PETSC_EXTERN PetscErrorCode KergsSceneGetSamplePath(KergsScene, const char **path);

/* Accessors. */
PETSC_EXTERN PetscErrorCode KergsSceneGetDisks(KergsScene, KergsDisks *);
/* The walls (replicated on every rank); their positions and velocities are the scene's to change. */
PETSC_EXTERN PetscErrorCode KergsSceneGetWalls(KergsScene, PetscInt *nwalls, const KergsWall **walls);
/* Where the four walls of -box stand now, as x0,y0,x1,y1 (they move by translation only); has is false without all four. */
PETSC_EXTERN PetscErrorCode KergsSceneGetBox(KergsScene, PetscBool *has, PetscReal box[4]);
PETSC_EXTERN PetscErrorCode KergsSceneGetName(KergsScene, const char **name);
PETSC_EXTERN PetscErrorCode KergsSceneGetComm(KergsScene, MPI_Comm *);
PETSC_EXTERN PetscErrorCode KergsSceneGetTimeStep(KergsScene, PetscReal *dt, PetscReal *theta);
/* Steps taken, scene time, and the number of steps the run asks for (-steps). */
PETSC_EXTERN PetscErrorCode KergsSceneGetStep(KergsScene, PetscInt *step, PetscReal *time, PetscInt *nsteps);
PETSC_EXTERN PetscErrorCode KergsSceneGetGravity(KergsScene, PetscReal gravity[]);
/* Materials: their number and the friction table mu[a * nmaterials + b] (symmetric). */
PETSC_EXTERN PetscErrorCode KergsSceneGetMaterials(KergsScene, PetscInt *nmaterials, const PetscReal **mu);
/* Alert distance (potential contacts have a gap below it) and the rule deciding which of them are active. */
PETSC_EXTERN PetscErrorCode KergsSceneGetContactRule(KergsScene, PetscReal *alert, KergsGapRule *rule);
/* The automatic alert distance (-alert not given), before a step's detection: its floor (0.1 * mean radius) or twice
   the distance two bodies approaching at closing_speed close in a step, whichever is larger, at most twice the mean
   radius. A given -alert is kept. */
PETSC_EXTERN PetscErrorCode KergsSceneAdaptAlert(KergsScene, PetscReal closing_speed);
/* Whether the alert distance is automatic, and its floor (0 when -alert is given). */
PETSC_EXTERN PetscErrorCode KergsSceneGetAlertFloor(KergsScene, PetscBool *automatic, PetscReal *floor);
/* What the scene models: frictional (some material pair has mu > 0: contacts carry a tangential component) and
   rotating (frictional disks not locked by -disks_lock_rotation: a rotational DOF per disk). */
PETSC_EXTERN PetscErrorCode KergsSceneGetModel(KergsScene, PetscBool *frictional, PetscBool *rotating);
/* The end of a time step (Algorithm 1): the owned disks' and free walls' new velocities are already in place;
   x+ = x- + dt (theta V+ + (1 - theta) V-) for them with V- = (vold, wold, wvold: per owned disk KERGS_DIM and
   KERGS_NROT values, per wall KERGS_DIM), driven walls move with their velocity of the step, and the clock advances by
   one step. The ghosts are not refreshed (KergsSceneRefreshGhosts). */
PETSC_EXTERN PetscErrorCode KergsSceneAdvance(KergsScene, const PetscReal vold[], const PetscReal wold[], const PetscReal wvold[]);
/* Set wall w's velocity (KERGS_DIM values): a driven wall's for the step (its program's, set by the assembly), a free
   wall's new one (the velocity update). Disks' velocities are written through KergsDisks. */
PETSC_EXTERN PetscErrorCode KergsSceneSetWallVelocity(KergsScene, PetscInt w, const PetscReal v[]);

/* Restart from a checkpoint (src/io/checkpoint.c). KergsSceneSetRestoring, before KergsSceneSetFromOptions: the disk
   options are read (so that -help lists them and none counts as unused) but no disks are built and KergsSceneCheck is
   left to the caller, once the state is restored. */
PETSC_EXTERN PetscErrorCode KergsSceneSetRestoring(KergsScene, PetscBool);
/* Collective: this rank owns the nowned disks given (its global indices follow the previous ranks'), with all their
   state; masses and inertias from the materials' densities; no ghost layer. */
PETSC_EXTERN PetscErrorCode KergsSceneRestoreDisks(KergsScene, PetscInt ndisks, PetscInt nowned, const PetscInt id[],
                                                   const PetscInt material[], const PetscReal x[], const PetscReal rot[],
                                                   const PetscReal v[], const PetscReal omega[], const PetscReal radius[]);
/* The clock, and the automatic alert distance and its floor as the run left them (with -alert given, this run's value
   is kept: the checkpointed run's, or the command line's). */
PETSC_EXTERN PetscErrorCode KergsSceneRestoreState(KergsScene, PetscInt step, PetscReal time, PetscReal alert, PetscReal alert_floor);
/* Wall w's loaded length (KergsWall.span): what its pressure multiplies. */
PETSC_EXTERN PetscErrorCode KergsSceneWallLoadedLength(KergsScene, PetscInt w, PetscReal *length);
/* Wall w's endpoints, velocity and displacement since the start of the run (KERGS_DIM values each) */
PETSC_EXTERN PetscErrorCode KergsSceneRestoreWall(KergsScene, PetscInt w, const PetscReal a[], const PetscReal b[], const PetscReal v[],
                                                  const PetscReal disp[]);
/* The ghost layer as a checkpoint keeps it (src/scene/ghosts.c): whether it exists, the owned disks' positions when it
   was built (xref, KERGS_DIM per owned disk) and its margin, the alert distance plus the skin then (both decide when
   it is rebuilt), and the number of layers built so far. The ghosts themselves are the disks of global indices D.gidx[nowned..nlocal)
   (KergsSceneGetDisks). */
PETSC_EXTERN PetscErrorCode KergsSceneGetGhostState(KergsScene, PetscBool *layer, const PetscReal **xref, PetscReal *margin,
                                                    PetscInt *rebuilds);
/* Collective, after KergsSceneRestoreDisks on the same ranks as the checkpointed run: the ghost layer of the given
   global indices (in that local order, fetched from their owners with their whole state), its xref, margin and count,
   as if never interrupted (a negative margin, from a checkpoint that has none: the alert plus the skin, the rule of
   its time). With layer false no layer is built (the next detection builds one). */
PETSC_EXTERN PetscErrorCode KergsSceneRestoreGhosts(KergsScene, PetscBool layer, PetscInt nghosts, const PetscInt gidx[],
                                                    const PetscReal xref[], PetscReal margin, PetscInt rebuilds);

/* Distributed state (src/scene/ghosts.c). */
/* Collective. Rebuild the ghost layer when asked, when there is none, or when the alert distance plus twice the
   largest displacement of a disk since the last build exceeds that build's alert + ghost skin (with a fixed alert: a
   disk moved more than half the skin); otherwise leave it (its state is current after KergsSceneRefreshGhosts).
   After a build, every disk of another rank whose centre is within 2 max(R) + alert + ghost_skin of this rank's
   bounding box of owned centres is a ghost here, so every pair of disks within the alert distance has both disks
   on the owner rank of each. A rebuild renumbers the ghosts: local indices of ghosts (contacts' b) are valid
   until the next rebuild only. */
PETSC_EXTERN PetscErrorCode KergsSceneUpdateGhosts(KergsScene, PetscBool rebuild);
/* Collective. Copy the positions, orientations and velocities of every ghost from its owner (one neighbour
   exchange through ghost_sf); no-op without a layer. */
PETSC_EXTERN PetscErrorCode KergsSceneRefreshGhosts(KergsScene);
/* Collective. Move the owned disks to their new owners: owned disk i gets the global index newidx[i]; rank p then
   owns counts[p] disks, global indices from counts[0] + ... + counts[p-1] (counts the same on every rank). Drops
   the ghost layer. */
PETSC_EXTERN PetscErrorCode KergsSceneMigrate(KergsScene, const PetscInt newidx[], const PetscInt counts[]);
/* Collective. Gather a per-disk array of the owned disks (bs values per disk) in global-index order on every rank
   (all: bs * ndisks values). For tests, tools and small scenes: O(ndisks) memory on every rank. */
PETSC_EXTERN PetscErrorCode KergsSceneAllGatherReal(KergsScene, const PetscReal owned[], PetscInt bs, PetscReal all[]);
PETSC_EXTERN PetscErrorCode KergsSceneAllGatherInt(KergsScene, const PetscInt owned[], PetscInt bs, PetscInt all[]);

#endif
