/* kergs detect: contact detection. Broad phase by cell lists (O(N)), narrow phase disk-disk and
   disk-wall, gaps, local frames, potential contacts within the alert distance, and persistence:
   a contact keeps its impulse from one step to the next when the same pair of bodies touches again
   (warm start of Algorithm 1). */
#ifndef KERGS_DETECT_H
#define KERGS_DETECT_H

#include <kergs/scene.h>

typedef enum { KERGS_CONTACT_DISK_DISK, KERGS_CONTACT_DISK_WALL } KergsContactKind;

/* One contact. Body a is always a disk owned by this rank (a local disk index); body b is a disk (a local index,
   owned or ghost) of larger grain id, or a wall (its index). The normal n points from b towards a, the tangent is
   t = (-n_y, n_x). Contact point c: c - x_a = -ra n, c - x_b = +rb n (rb = 0 for a wall).
   Ownership: a disk-disk contact belongs to the rank that owns its disk of smaller grain id, a disk-wall contact
   to the rank that owns the disk; grain ids never change, so neither does a contact's owner-side orientation when
   disks migrate. */
typedef struct {
  KergsContactKind kind;
  PetscInt         a, b;
  PetscInt         idb; /* persistent identity of b: its grain id, or the wall index */
  PetscReal        n[KERGS_DIM], t[KERGS_DIM];
  PetscReal        ra, rb;
  PetscReal        gap;              /* g^- : gap at the start of the step (negative = interpenetration) */
  PetscReal        mu;               /* friction coefficient of the material pair */
  PetscReal        r[KERGS_MAXCOMP]; /* impulse (n, t): warm start in, solution out */
  PetscBool        persistent;       /* the pair touched at the previous detection too */
} KergsContact;

/* What a contact leaves to the next detection (warm start): its key (a, kind, idb) and its impulse. */
typedef struct {
  PetscInt         a, idb;
  KergsContactKind kind;
  PetscReal        r[KERGS_MAXCOMP];
} KergsContactHistory;

/* Order of contacts and of their histories (any records with a, kind, idb): -1, 0 or 1. */
#define KERGS_COMPARE_KEYS(p, q)                                                                                                           \
  ((p)->a != (q)->a         ? ((p)->a < (q)->a ? -1 : 1)                                                                                   \
   : (p)->kind != (q)->kind ? ((p)->kind < (q)->kind ? -1 : 1)                                                                             \
   : (p)->idb != (q)->idb   ? ((p)->idb < (q)->idb ? -1 : 1)                                                                               \
                            : 0)
/* qsort comparator of KergsContactHistory records by key */
PETSC_EXTERN int KergsContactHistoryCompare(const void *, const void *);

typedef struct _p_KergsContacts *KergsContacts;

PETSC_EXTERN PetscErrorCode KergsContactsCreate(MPI_Comm, KergsContacts *);
/* Find every potential contact (gap < scene->alert) owned by this rank, among its owned disks and their ghosts
   (it first calls KergsSceneUpdateGhosts, which rebuilds the ghost layer when needed), carry impulses over from the previous call for
   persistent pairs (zero for new ones), and set nglobal and start (collective). O(local disks). */
PETSC_EXTERN PetscErrorCode KergsContactsDetect(KergsContacts, KergsScene);
PETSC_EXTERN PetscErrorCode KergsContactsDestroy(KergsContacts *);
/* Accessors. The owned contacts, sorted by key (a, kind, idb); their impulses r may be written (the solve's result). */
PETSC_EXTERN PetscErrorCode KergsContactsGetLocal(KergsContacts, PetscInt *n, KergsContact **c);
/* The foreign contacts: disk-disk contacts owned by another rank (their body a is a ghost here, of smaller grain id)
   whose body b is a disk owned here, with their global indices. With the owned contacts they are every contact at an
   owned disk, as the assembly of W needs (each rank adds its own bodies' terms). */
PETSC_EXTERN PetscErrorCode KergsContactsGetForeign(KergsContacts, PetscInt *n, const KergsContact **c, const PetscInt **index);
/* Global index of this rank's first contact (contacts are numbered rank after rank) and the global count. */
PETSC_EXTERN PetscErrorCode KergsContactsGetGlobalRange(KergsContacts, PetscInt *start, PetscInt *nglobal);
/* Collective, when the disks migrate (partition): every contact goes to the new owner of its disk a, where it is kept
   only as its key and impulse (b = -1) until the next detection, which carries the impulses over; nothing else may
   read it before then. newidx[i]: new global index of owned disk i; newranges: the ranks' new index ranges (size + 1
   entries). Call before the disks move. */
PETSC_EXTERN PetscErrorCode KergsContactsMigrate(KergsContacts, const PetscInt newidx[], const PetscInt newranges[]);
/* Collective, for a restart from a checkpoint (src/io/checkpoint.c): the owned contacts become the n given, in that order
   (sorted by key, as detection leaves them), with the global numbering; no foreign contacts until the next detection.
   Contacts holding only their key and impulse (b = -1, as KergsContactsMigrate leaves them) warm-start the next
   detection and may be read by nothing else before it. */
PETSC_EXTERN PetscErrorCode KergsContactsRestore(KergsContacts, PetscInt n, const KergsContact c[]);
/* Which contacts are active this step (eq. 2: the law applies when the predicted gap g~ <= 0, otherwise r = 0). The
   paper's rule: g~ = g^-; LMGC90's: g~ = g^- + (1 - theta) dt v_n^-, v_n^- = n.(V_a - V_b) from the velocities at the
   start of the step (a wall's: its velocity of the step, as the assembly sets it). Decided from the contact and its
   bodies' state alone, so that every rank holding a contact decides alike. KergsContactsGetActivity fetches the
   rule and the state it reads (valid while the disks and walls do not change); KergsContactIsActive applies it to
   one contact, owned or foreign. */
typedef struct {
  KergsGapRule     rule;
  PetscReal        lead;     /* (1 - theta) dt */
  PetscReal        theta_dt; /* theta dt */
  const PetscReal *v;        /* disk velocities (local indices) */
  const KergsWall *walls;
} KergsActivity;
PETSC_EXTERN PetscErrorCode KergsContactsGetActivity(KergsContacts, KergsScene, KergsActivity *);
PETSC_EXTERN PetscBool      KergsContactIsActive(const KergsActivity *, const KergsContact *);
/* The predictive rule's normal velocity offset of an active contact, max(g~, 0) / (theta dt) with the LMGC90 g~ (0 for
   the other rules): Signorini is written on v_n + offset >= 0, so that the gap at the end of the step,
   g~ + theta dt v_n, stays >= 0 while an open contact may close during the step. */
PETSC_EXTERN PetscReal KergsContactGapVelocity(const KergsActivity *, const KergsContact *);

#endif
