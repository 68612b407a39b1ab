/* kergs scene: the bodies (disks, walls), materials, loading programs and numerical settings of a run.
   A scene is read from the options database (an options file under cases/); its disks come from a
   built-in generator (lattice, random) or from a sample file written by an earlier run.
   The disk state is replicated on every rank; each rank owns a contiguous range of disks
   [dstart, dend) for the distributed operators (see DESIGN.md section 6). */
#ifndef KERGS_SCENE_H
#define KERGS_SCENE_H

#include <kergs/base.h>

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
  /* disks (replicated, structure of arrays, global index i) */
  PetscInt   ndisks;
  PetscInt  *id;       /* persistent grain id */
  PetscReal *x;        /* KERGS_DIM * ndisks positions */
  PetscReal *rot;      /* KERGS_NROT * ndisks orientations */
  PetscReal *v;        /* KERGS_DIM * ndisks velocities */
  PetscReal *omega;    /* KERGS_NROT * ndisks angular velocities */
  PetscReal *radius, *mass, *inertia;
  PetscInt  *material;
  PetscInt   dstart, dend; /* disks owned by this rank */
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
/* Collective. Replaces the disks: x (KERGS_DIM * n), r (n); material and v may be NULL (material 0, at rest).
   Sets id = index, rot = omega = 0, mass and inertia from the densities, dstart/dend, recomputes frictional,
   and sets alert = 0.1 * mean radius if alert is still automatic (negative). */
PETSC_EXTERN PetscErrorCode KergsSceneSetDisks(KergsScene, PetscInt n, const PetscReal *x, const PetscReal *r, const PetscInt *material, const PetscReal *v);
/* Errors naming the grain, wall, material pair or option at fault; overlaps are not checked here. */
PETSC_EXTERN PetscErrorCode KergsSceneCheck(KergsScene);
PETSC_EXTERN PetscErrorCode KergsSceneView(KergsScene, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsSceneDestroy(KergsScene *);
PETSC_EXTERN PetscErrorCode KergsSceneFriction(KergsScene, PetscInt mat_a, PetscInt mat_b, PetscReal *mu);
/* Driven wall: its program's velocity at time t (zero before the first piece or without program).
   Free wall: its current velocity wall->v. */
PETSC_EXTERN PetscErrorCode KergsWallVelocityAt(const KergsWall *, PetscReal t, PetscReal v[]);
/* Over all disks (replicated, no communication): ek = sum 1/2 m |v|^2 + 1/2 I omega^2, vmax = largest speed. */
PETSC_EXTERN PetscErrorCode KergsSceneKineticEnergy(KergsScene, PetscReal *ek, PetscReal *vmax);

#endif
