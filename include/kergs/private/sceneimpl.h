/* kergs scene, private: the scene object's fields, for the scene's own files (src/scene/) only; every other
   component goes through the accessors of kergs/scene.h. */
#ifndef KERGS_SCENEIMPL_H
#define KERGS_SCENEIMPL_H

#include <kergs/scene.h>

struct _p_KergsScene {
  MPI_Comm comm;
  char     name[PETSC_MAX_PATH_LEN];
  /* disks: local structure of arrays, owned disks [0, nowned) then ghosts [nowned, nlocal) */
  PetscInt   ndisks;         /* global number of disks */
  PetscInt   nowned, nlocal; /* disks owned here; owned + ghosts */
  PetscInt   nalloc;         /* capacity of the local arrays */
  PetscInt  *gidx;           /* global index (owned disk i: dstart + i) */
  PetscInt  *id;             /* persistent grain id */
  PetscReal *x;              /* KERGS_DIM * ndisks positions */
  PetscReal *rot;            /* KERGS_NROT * ndisks orientations */
  PetscReal *v;              /* KERGS_DIM * ndisks velocities */
  PetscReal *omega;          /* KERGS_NROT * ndisks angular velocities */
  PetscReal *radius, *mass, *inertia;
  PetscInt  *material;
  PetscInt   dstart, dend; /* global indices of the disks owned by this rank */
  /* ghost layer (src/scene/ghosts.c) */
  PetscSF    ghost_sf;       /* roots: owned disks, leaves: ghosts (NULL: no valid ghost layer) */
  PetscInt  *ghost_owner;    /* per ghost: the rank that owns it */
  PetscReal  ghost_skin;     /* -ghost_skin: the layer reaches alert + skin beyond the owned disks (ghost_margin) */
  PetscReal *xref;           /* owned positions when the layer was built */
  PetscInt   ghost_rebuilds; /* layers built so far */
  PetscReal  ghost_margin;   /* alert + skin of the last build: rebuilt once alert + 2 dmax exceeds it */
  /* walls (replicated) */
  PetscInt   nwalls;
  KergsWall *walls;
  /* materials */
  PetscInt   nmaterials;
  PetscReal *density;       /* per material (mass per unit area in 2D) */
  PetscReal *mu;            /* friction coefficient, nmaterials x nmaterials, symmetric */
  PetscBool  frictional;    /* some pair has mu > 0: contacts carry tangential components, disks rotate */
  PetscBool  lock_rotation; /* -disks_lock_rotation: disks translate only (sliding blocks), no rotation DOFs */
  /* loading and numerics */
  PetscReal    gravity[KERGS_DIM];
  PetscReal    dt, theta;
  PetscInt     nsteps;
  KergsGapRule gaprule;
  PetscReal    alert;       /* alert distance: potential contacts have gap < alert */
  PetscBool    alert_auto;  /* -alert not given: the alert follows the speed (KergsSceneAdaptAlert) */
  PetscReal    alert_floor; /* then its smallest value, 0.1 * mean radius */
  /* clock */
  PetscInt  step;
  PetscReal time;
  /* restart (KergsSceneSetRestoring): the disks come from a checkpoint, not from the disk source options */
  PetscBool restoring;
  /* the sample file the disks were read from (KergsSampleRead), empty otherwise */
  char sample_path[PETSC_MAX_PATH_LEN];
};

/* Shared by the scene's files. */
/* Reads the disk source options (-disks_source list|lattice|random|file and theirs) and sets the disks
   (src/scene/disks.c). */
PETSC_INTERN PetscErrorCode KergsSceneDisksSetFromOptions(KergsScene);

/* The walls (src/scene/walls.c). Which walls there are (-box, -box_open_top, -walls) is read inside the scene's options
   block by KergsSceneWallsOptions; each wall then has an options block of its own (prefix wall_<name>_), read by
   KergsSceneSetWalls once the scene's block has ended. */
typedef struct {
  PetscBool box_set, open_top, box_from_sample, affine_start;
  PetscReal box[4]; /* x0,y0,x1,y1 */
  PetscInt  nnames;
  char    **names; /* the names given to -walls */
} KergsWallsSpec;
PETSC_INTERN PetscErrorCode KergsSceneWallsOptions(PetscOptionItems *, KergsWallsSpec *);
/* Replaces the scene's walls by the box walls, then the named walls, each read from its options; frees spec's names. */
PETSC_INTERN PetscErrorCode KergsSceneSetWalls(KergsScene, KergsWallsSpec *);
/* The walls' part of KergsSceneAdvance; wvold: the walls' velocities before the update (KERGS_DIM per wall). */
PETSC_INTERN PetscErrorCode KergsSceneAdvanceWalls(KergsScene, const PetscReal wvold[]);
PETSC_INTERN PetscErrorCode KergsSceneCheckWalls(KergsScene);
/* -box_affine_start: add to every grain's velocity the homogeneous deformation the box walls' velocities impose. */
PETSC_INTERN PetscErrorCode KergsSceneBoxAffineStart(KergsScene);
PETSC_INTERN PetscErrorCode KergsSceneViewWalls(KergsScene, PetscViewer);

/* Neither infinite nor NaN: the checks of the input. */
static inline PetscBool KergsSceneFinite(PetscReal v) { return PetscIsInfOrNanReal(v) ? PETSC_FALSE : PETSC_TRUE; }

#endif
