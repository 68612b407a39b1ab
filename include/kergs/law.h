/* kergs law: the exact one-contact solve of the 2D Signorini-Coulomb law (docs/design.md: the per-step problem).
   Problem: v = Waa r + b, with Waa the contact's diagonal block (ncomp x ncomp, row-major, symmetric
   positive definite), b the rest of the local velocity. Unknown r = (r_n, r_t):
     inactive (predicted gap > 0):  r = 0
     active: 0 <= v_n _|_ r_n >= 0, |r_t| <= mu r_n, v_t = 0 if |r_t| < mu r_n, r_t = -mu r_n sign(v_t) if sliding.
   Solved by cases (open, stick, slip with v_t > 0, slip with v_t < 0), no iteration. */
#ifndef KERGS_LAW_H
#define KERGS_LAW_H

#include <kergs/base.h>

typedef enum {
  KERGS_LAW_INACTIVE = 0, /* predicted gap positive: r = 0 */
  KERGS_LAW_OPEN,         /* active but separating: r = 0, v_n >= 0 */
  KERGS_LAW_STICK,        /* v = 0 */
  KERGS_LAW_SLIP_POS,     /* v_n = 0, v_t > 0, r_t = -mu r_n */
  KERGS_LAW_SLIP_NEG      /* v_n = 0, v_t < 0, r_t = +mu r_n */
} KergsLawStatus;

/* Exact solve; ncomp is 1 (frictionless, normal only) or 2. */
PETSC_EXTERN KergsLawStatus KergsLawSolve(PetscInt ncomp, const PetscReal Waa[], const PetscReal b[], PetscReal mu, PetscBool active,
                                          PetscReal r[]);

/* Squared norm of the natural-map residual of one contact,
     r - proj_K(r - rho (v + mu |v_t| e_n))    (De Saxce's modified velocity; K: Coulomb cone),
   or r itself when inactive. rho > 0 converts velocities to impulses (kergs uses rho = 1 / Waa_nn). */
/* The natural map itself, e = r - proj_K(r - rho (v + mu |v_t| e_n)) (e = r when inactive), into e[ncomp]. */
PETSC_EXTERN void      KergsLawNaturalMap(PetscInt ncomp, const PetscReal r[], const PetscReal v[], PetscReal mu, PetscReal rho,
                                          PetscBool active, PetscReal e[]);
PETSC_EXTERN PetscReal KergsLawNaturalResidual2(PetscInt ncomp, const PetscReal r[], const PetscReal v[], PetscReal mu, PetscReal rho,
                                                PetscBool active);
/* The natural residual of a whole problem from sums over its contacts: e2 = sum |e|^2, r2 = sum |r|^2 and p2 = sum |p|^2
   with p = r - e = proj_K(r - rho v~), the impulse the law maps r to. Returns |e| / max(|r|, |p|): relative, 0 when
   e = 0, and 1 at r = 0 when e is not 0 (|p| = |e| there). Near a solution p and r agree, so it is |e| / |r|; an
   absolute |e| at r = 0 had let a solver stop at r = 0 when the step's velocities were small. */
static inline PetscReal KergsLawNaturalResidualScaled(PetscReal e2, PetscReal r2, PetscReal p2)
{
  const PetscReal scale = PetscSqrtReal(PetscMax(r2, p2));
  return scale > 0 ? PetscSqrtReal(e2) / scale : 0.0;
}

/* The Alart-Curnier function of one contact (for Newton methods), with u = W r + b the local velocity, rho > 0:
     xi = r_n - rho u_n,  F_n = r_n - max(0, xi),  tau = mu max(0, xi),  F_t = r_t - proj_[-tau, tau](r_t - rho u_t)
   (F = r when inactive). F = 0 exactly when (r, u) satisfy the law. When A is not NULL, A and B (ncomp x ncomp,
   row-major) receive an element of the generalized Jacobian: dF = A dr + B du (so J = A + B W). */
PETSC_EXTERN void KergsLawAlartCurnier(PetscInt ncomp, const PetscScalar r[], const PetscScalar u[], PetscReal mu, PetscReal rho,
                                       PetscBool active, PetscReal F[], PetscReal A[], PetscReal B[]);
/* The same function with every max(0, x) replaced by its Chen-Harker-Kanzow-Smale smoothing
   phi_eps(x) = (x + sqrt(x^2 + 4 eps^2)) / 2 (eps > 0, in units of r): proj_[-tau, tau](z) = z - phi(z - tau) + phi(-z - tau),
   so F_t = rho u_t + phi(z - tau) - phi(-z - tau). F is smooth and tends to KergsLawAlartCurnier's as eps -> 0; A and B
   are its Jacobian, whose diagonal parts lie strictly between those of the pieces it joins. */
PETSC_EXTERN void KergsLawAlartCurnierSmoothed(PetscInt ncomp, const PetscScalar r[], const PetscScalar u[], PetscReal mu, PetscReal rho,
                                               PetscBool active, PetscReal eps, PetscReal F[], PetscReal A[], PetscReal B[]);

#endif
