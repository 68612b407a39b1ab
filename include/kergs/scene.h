/* kergs scene: the bodies (disks, walls), materials, loading programs and numerical settings of a run.
   A scene is read from the options database (an options file under cases/); its disks come from a
   built-in generator (lattice, random) or from a sample file written by an earlier run.
   The disk state is distributed (DESIGN.md section 6): rank p owns the disks of the global index range
   [dstart, dend), stored first in its local arrays, followed by ghost copies of other ranks' disks that can
   touch its own (src/scene_ghosts.c). A disk's global index is its place in the current partition's numbering
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
  KERGS_GAP_PAPER, /* predicted gap g~ = g^- (Alart 2013) */
  KERGS_GAP_LMGC90 /* g~ = g^- + (1 - theta) dt v_n^- (LMGC90) */
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
  /* free wall: translational mass and applied force (pressure x length) */
  PetscReal mass, force[KERGS_DIM];
  PetscReal v[KERGS_DIM];    /* current velocity */
  PetscReal disp[KERGS_DIM]; /* displacement since the start of the run */
} KergsWall;

typedef struct _p_KergsScene *KergsScene;
struct _p_KergsScene {
  MPI_Comm comm;
  char     name[PETSC_MAX_PATH_LEN];
  /* disks: local structure of arrays, owned disks [0, nowned) then ghosts [nowned, nlocal) */
  PetscInt   ndisks;           /* global number of disks */
  PetscInt   nowned, nlocal;   /* disks owned here; owned + ghosts */
  PetscInt   nalloc;           /* capacity of the local arrays */
  PetscInt  *gidx;     /* global index (owned disk i: dstart + i) */
  PetscInt  *id;       /* persistent grain id */
  PetscReal *x;        /* KERGS_DIM * ndisks positions */
  PetscReal *rot;      /* KERGS_NROT * ndisks orientations */
  PetscReal *v;        /* KERGS_DIM * ndisks velocities */
  PetscReal *omega;    /* KERGS_NROT * ndisks angular velocities */
  PetscReal *radius, *mass, *inertia;
  PetscInt  *material;
  PetscInt   dstart, dend; /* global indices of the disks owned by this rank */
  /* ghost layer (src/scene_ghosts.c) */
  PetscSF    ghost_sf;       /* roots: owned disks, leaves: ghosts (NULL: no valid ghost layer) */
  PetscInt  *ghost_owner;    /* per ghost: the rank that owns it */
  PetscReal  ghost_skin;     /* -ghost_skin: the layer is rebuilt once some disk moved more than half of it */
  PetscReal *xref;           /* owned positions when the layer was built */
  PetscInt   ghost_rebuilds; /* layers built so far */
  /* walls (replicated) */
  PetscInt   nwalls;
  KergsWall *walls;
  /* materials */
  PetscInt   nmaterials;
  PetscReal *density; /* per material (mass per unit area in 2D) */
  PetscReal *mu;      /* friction coefficient, nmaterials x nmaterials, symmetric */
  PetscBool  frictional; /* some pair has mu > 0: contacts carry tangential components, disks rotate */
  PetscBool  lock_rotation; /* -disks_lock_rotation: disks translate only (sliding blocks), no rotation DOFs */
  /* loading and numerics */
  PetscReal    gravity[KERGS_DIM];
  PetscReal    dt, theta;
  PetscInt     nsteps;
  KergsGapRule gaprule;
  PetscReal    alert; /* alert distance: potential contacts have gap < alert */
  /* clock */
  PetscInt  step;
  PetscReal time;
};

/* Defaults: gravity (0, -9.81), dt 1e-3, 100 steps, theta 1, paper gap rule, one material of density 1 without
   friction, alert automatic (negative until disks are set), no disks, no walls. */
PETSC_EXTERN PetscErrorCode KergsSceneCreate(MPI_Comm, KergsScene *);
/* Reads every scene option (run with -help for the list), generates the disks, then calls KergsSceneCheck. */
PETSC_EXTERN PetscErrorCode KergsSceneSetFromOptions(KergsScene);
/* Collective. Replaces the disks by the n disks given, the same arrays on every rank: x (KERGS_DIM * n), r (n);
   material and v may be NULL (material 0, at rest). Each rank keeps its slice of the even contiguous split as its
   owned disks (no ghosts yet). Sets id = global index, rot = omega = 0, mass and inertia from the densities,
   recomputes frictional, and sets alert = 0.1 * mean radius if alert is still automatic (negative). */
PETSC_EXTERN PetscErrorCode KergsSceneSetDisks(KergsScene, PetscInt n, const PetscReal *x, const PetscReal *r, const PetscInt *material, const PetscReal *v);
/* Errors naming the grain, wall, material pair or option at fault; overlaps are not checked here. */
PETSC_EXTERN PetscErrorCode KergsSceneCheck(KergsScene);
PETSC_EXTERN PetscErrorCode KergsSceneView(KergsScene, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsSceneDestroy(KergsScene *);
PETSC_EXTERN PetscErrorCode KergsSceneFriction(KergsScene, PetscInt mat_a, PetscInt mat_b, PetscReal *mu);
/* Driven wall: its program's velocity at time t (zero before the first piece or without program).
   Free wall: its current velocity wall->v. */
PETSC_EXTERN PetscErrorCode KergsWallVelocityAt(const KergsWall *, PetscReal t, PetscReal v[]);
/* Collective, over all disks: ek = sum 1/2 m |v|^2 + 1/2 I omega^2, vmax = largest speed. */
PETSC_EXTERN PetscErrorCode KergsSceneKineticEnergy(KergsScene, PetscReal *ek, PetscReal *vmax);
/* Make room for n local disks (owned + ghosts), keeping the first nlocal. */
PETSC_EXTERN PetscErrorCode KergsSceneReserve(KergsScene, PetscInt n);

/* Distributed state (src/scene_ghosts.c). */
/* Collective. Rebuild the ghost layer when asked, when there is none, or when some disk moved more than
   ghost_skin / 2 since the last build; otherwise leave it (its state is current after KergsSceneRefreshGhosts).
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
