/* newton's interior-point start (-solver_newton_ip_max_it): Mehrotra's predictor-corrector on the 2D law written as the
   linear complementarity problem of Stewart and Trinkle, before Newton (docs/solver.md, "An interior-point start").

   Per contact x = (r_n, beta+, beta-, lambda) >= 0, r_t = beta+ - beta-, and w = M x + c >= 0 complementary to x:
     w = (rho u_n, rho u_t + lambda, -rho u_t + lambda, mu r_n - beta+ - beta-),   u = W r + v^d,
   rho = 1 / W_nn, so that every pair is in impulse units. M = S W T + G: T x = r, S (4 x 2) scales u, G (4 x 4) is
   local. The LCP is not monotone once mu > 0, so the interior point has no convergence theory; measured, it puts
   the answer on the solution's pieces where Newton from zero stalls (dense frictional packings at rest).

   Each iteration solves (M + X^-1 W) dx = g twice (predictor, corrector). With K = G + X^-1 W block diagonal, y = T dx
   satisfies the nc x nc per contact system (I + T K^-1 S W) y = T K^-1 g, which is newton's J = A + B W with A = I and
   B = T K^-1 S: assembled and factored by newton's own linear solver, once per iteration. Then dx = K^-1 (g - S W y).

   Without friction (one component per contact) the LCP is the normal problem alone: x = r_n, w = rho u_n, T = 1,
   S = rho, G = 0, so M = rho W: W's LCP scaled row by row, with the same solutions. A positive diagonal times a positive
   semidefinite matrix is sufficient (P*), the class for which the interior point's convergence theory holds (Kojima,
   Megiddo, Noma and Yoshise, LNCS 538, 1991), where the frictional M is not. K = w / x, and J = 1 + (x / w) rho W with
   each row divided by rho x / w is w / (rho x) + W: symmetric positive definite, factored by Cholesky.

   With newton's working set the problem holds the contacts the working set would put in J at the warm start, and
   those an iterate closes join it (JoinClosingContacts); the others keep r = 0. */
#include "newton.h"

#define NX_MAX 4 /* unknowns of x per contact: 4 with friction (the size of K, Invert4's), 1 without */

typedef struct {
  PetscInt   n;         /* local contacts */
  PetscInt   nc, nx;    /* components of r per contact (2 or 1) and unknowns of x per contact (4 or 1) */
  PetscBool *in;        /* per contact: in the problem (active, and in J when newton keeps a working set) */
  PetscReal *x, *w;     /* per contact nx */
  PetscReal *f1;        /* w - M x - c */
  PetscReal *Kinv;      /* per contact nx x nx, row-major */
  PetscReal *dxa, *dwa; /* the predictor's direction */
  PetscReal *dx, *dw;   /* the corrector's */
  PetscReal *g;         /* the right-hand side of (M + X^-1 W) dx = g */
  PetscReal *target;    /* the corrector's target for x.w */
  PetscInt   nglobal;   /* contacts in the problem, all ranks */
  KSP        ksp;       /* the start's own direct solver for J (CreateDirectSolver), or NULL: newton's */
} InteriorPoint;

/* The inverse of a 4 x 4 matrix by Gauss-Jordan elimination with partial pivoting; false if singular. */
static PetscBool Invert4(const PetscReal a[NX_MAX * NX_MAX], PetscReal inv[NX_MAX * NX_MAX])
{
  PetscReal m[NX_MAX][2 * NX_MAX];

  for (PetscInt i = 0; i < NX_MAX; i++)
    for (PetscInt j = 0; j < NX_MAX; j++) {
      m[i][j]          = a[i * NX_MAX + j];
      m[i][NX_MAX + j] = i == j ? 1.0 : 0.0;
    }
  for (PetscInt c = 0; c < NX_MAX; c++) {
    PetscInt p = c;
    for (PetscInt i = c + 1; i < NX_MAX; i++)
      if (PetscAbsReal(m[i][c]) > PetscAbsReal(m[p][c])) p = i;
    if (!(PetscAbsReal(m[p][c]) > 0)) return PETSC_FALSE;
    for (PetscInt j = 0; j < 2 * NX_MAX; j++) {
      const PetscReal t = m[c][j];
      m[c][j]           = m[p][j];
      m[p][j]           = t;
    }
    const PetscReal piv = m[c][c];
    for (PetscInt j = 0; j < 2 * NX_MAX; j++) m[c][j] /= piv;
    for (PetscInt i = 0; i < NX_MAX; i++) {
      if (i == c || m[i][c] == 0) continue;
      const PetscReal f = m[i][c];
      for (PetscInt j = 0; j < 2 * NX_MAX; j++) m[i][j] -= f * m[c][j];
    }
  }
  for (PetscInt i = 0; i < NX_MAX; i++)
    for (PetscInt j = 0; j < NX_MAX; j++) inv[i * NX_MAX + j] = m[i][NX_MAX + j];
  return PETSC_TRUE;
}

/* r = T x on the problem's contacts (0 elsewhere), and u = W r + v^d. */
static PetscErrorCode ImpulsesFromX(Newton *nt, const InteriorPoint *ip, Vec r, Vec u, Vec vd)
{
  PetscScalar *rl;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(r, &rl));
  for (PetscInt a = 0; a < ip->n; a++) {
    const PetscReal *x = ip->x + ip->nx * a;
    rl[ip->nc * a]     = ip->in[a] ? x[0] : 0.0;
    if (ip->nc == 2) rl[2 * a + 1] = ip->in[a] ? x[1] - x[2] : 0.0;
  }
  PetscCall(VecRestoreArray(r, &rl));
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscFunctionReturn(0);
}

/* M x + c of contact a, from its x and its u = W r + v^d. */
static void LCPMap(const KergsSolver s, const Newton *nt, const InteriorPoint *ip, PetscInt a, const PetscReal x[NX_MAX],
                   const PetscScalar ul[], PetscReal mx[NX_MAX])
{
  const PetscReal rho = nt->rho_nat[a], un = PetscRealPart(ul[ip->nc * a]);

  mx[0] = rho * un;
  if (ip->nc == 1) return;
  const PetscReal ut = PetscRealPart(ul[2 * a + 1]);
  mx[1]              = rho * ut + x[3];
  mx[2]              = -rho * ut + x[3];
  mx[3]              = s->mu[a] * x[0] - x[1] - x[2];
}

/* f1 = w - M x - c at the current x (u current), and the mean complementarity x.w / N. */
static PetscErrorCode Residuals(KergsSolver s, Newton *nt, InteriorPoint *ip, Vec u, PetscReal *gap)
{
  const PetscScalar *ul;
  PetscReal          sum = 0.0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < ip->n; a++) {
    PetscReal mx[NX_MAX];
    if (!ip->in[a]) continue;
    LCPMap(s, nt, ip, a, ip->x + ip->nx * a, ul, mx);
    for (PetscInt i = 0; i < ip->nx; i++) {
      ip->f1[ip->nx * a + i] = ip->w[ip->nx * a + i] - mx[i];
      sum += ip->x[ip->nx * a + i] * ip->w[ip->nx * a + i];
    }
  }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, s->comm));
  *gap = sum / (ip->nx * PetscMax(ip->nglobal, 1));
  PetscFunctionReturn(0);
}

/* Per contact K = G + X^-1 W, its inverse, and J's blocks A = I, B = T K^-1 S (S = rho [[1, 0], [0, 1], [0, -1], [0, 0]]).
   Without friction K = w / x, and the row is divided by B = rho x / w: A = w / (rho x), B = 1, so that J = A + W is
   symmetric positive definite over the problem's contacts (CreateDirectSolver factors it by Cholesky; the right-hand
   side is divided alike, in Direction). J's other rows are those of inactive contacts, which newton's W does not
   couple (W over the active pairs: StoredBlock, delassus.c, by the rule that sets s->active), so they are rows and
   columns of the identity (W_ii times it in newton's symmetric form, SymmetricRows) and J stays symmetric. Newton's shift, 1e-8, is then
   added to a diagonal of order W_nn, not 1. Contacts outside the problem keep r = 0: A = I, B = 0. False on a rank where some K is
   singular. */
static PetscBool SetBlocks(KergsSolver s, Newton *nt, InteriorPoint *ip)
{
  const PetscInt nc = ip->nc, nx = ip->nx;

  for (PetscInt a = 0; a < ip->n; a++) {
    PetscReal *A = nt->A + nc * nc * a, *B = nt->B + nc * nc * a, *Ki = ip->Kinv + nx * nx * a;
    for (PetscInt i = 0; i < nc * nc; i++) {
      A[i] = i % (nc + 1) == 0 ? 1.0 : 0.0;
      B[i] = 0.0;
    }
    if (!ip->in[a]) continue;
    const PetscReal *x = ip->x + nx * a, *w = ip->w + nx * a, rho = nt->rho_nat[a];
    if (nc == 1) {
      Ki[0] = x[0] / w[0];
      A[0]  = 1.0 / (rho * Ki[0]);
      B[0]  = 1.0;
      /* x or w underflowed to 0, or A overflowed: a Cholesky factorization fails with an error, not a reason */
      if (!(x[0] > 0 && w[0] > 0 && PetscIsNormalReal(A[0]))) return PETSC_FALSE;
      continue;
    }
    PetscReal K[NX_MAX * NX_MAX] = {0};
    K[1 * NX_MAX + 3] = K[2 * NX_MAX + 3] = 1.0;
    K[3 * NX_MAX + 0]                     = s->mu[a];
    K[3 * NX_MAX + 1] = K[3 * NX_MAX + 2] = -1.0;
    for (PetscInt i = 0; i < NX_MAX; i++) K[i * NX_MAX + i] += w[i] / x[i];
    /* K is nonsingular while x, w > 0 (its row 0 is diagonal, its lower 3 x 3 block a positive diagonal plus a skew
       part); the check guards against x underflowing to 0 */
    if (!Invert4(K, Ki)) return PETSC_FALSE;
    /* B = T K^-1 S: K^-1 S's column col is K^-1 times S's column, rho (1, 0, 0, 0) for col 0 and rho (0, 1, -1, 0) for
       col 1; T then takes its entry 0, and its entry 1 minus entry 2 */
    for (PetscInt col = 0; col < 2; col++) {
      PetscReal Kcol[NX_MAX];
      for (PetscInt i = 0; i < NX_MAX; i++) Kcol[i] = rho * (col == 0 ? Ki[i * NX_MAX + 0] : Ki[i * NX_MAX + 1] - Ki[i * NX_MAX + 2]);
      B[0 * 2 + col] = Kcol[0];
      B[1 * 2 + col] = Kcol[1] - Kcol[2];
    }
  }
  return PETSC_TRUE;
}

/* y = K^-1 v of contact a (nx entries). */
static void ApplyKinv(const InteriorPoint *ip, PetscInt a, const PetscReal v[], PetscReal y[])
{
  const PetscReal *Ki = ip->Kinv + ip->nx * ip->nx * a;

  for (PetscInt i = 0; i < ip->nx; i++) {
    y[i] = 0.0;
    for (PetscInt j = 0; j < ip->nx; j++) y[i] += Ki[i * ip->nx + j] * v[j];
  }
}

/* One direction: g = f1 - (x.w - target) / x, J y = T K^-1 g (newton's linear solver or the start's; F = -T K^-1 g, and
   without friction F = -g / rho, as J's rows are divided by rho x / w), then dx = K^-1 (g - S W y) and
   dw = (target - x.w - w.dx) / x. target NULL: 0 (the predictor). */
static PetscErrorCode Direction(Newton *nt, InteriorPoint *ip, const PetscReal *target, PetscReal *dx, PetscReal *dw, PetscBool *solved)
{
  const PetscInt     nc = ip->nc, nx = ip->nx;
  PetscScalar       *Fl;
  const PetscScalar *wy;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(nt->F, &Fl));
  for (PetscInt a = 0; a < ip->n; a++) {
    for (PetscInt c = 0; c < nc; c++) Fl[nc * a + c] = 0.0;
    if (!ip->in[a]) continue;
    const PetscReal *x = ip->x + nx * a, *w = ip->w + nx * a;
    PetscReal       *g = ip->g + nx * a, Kg[NX_MAX];
    for (PetscInt i = 0; i < nx; i++) g[i] = ip->f1[nx * a + i] - (x[i] * w[i] - (target ? target[nx * a + i] : 0.0)) / x[i];
    ApplyKinv(ip, a, g, Kg);
    Fl[nc * a] = nc == 1 ? -g[0] / nt->rho_nat[a] : -Kg[0];
    if (nc == 2) Fl[2 * a + 1] = -(Kg[1] - Kg[2]);
  }
  PetscCall(VecRestoreArray(nt->F, &Fl));
  if (ip->ksp) {
    KSPConvergedReason reason;
    PetscCall(NewtonSolveSystem(nt, ip->ksp, &reason));
    *solved = (PetscBool)(reason > 0);
  } else
    PetscCall(NewtonSolveDirection(nt, ip->n, nc, solved));
  if (!*solved) PetscFunctionReturn(0);
  PetscCall(MatMult(nt->Wfull, nt->d, nt->Wd));
  PetscCall(VecGetArrayRead(nt->Wd, &wy));
  for (PetscInt a = 0; a < ip->n; a++) {
    if (!ip->in[a]) continue;
    const PetscReal *x = ip->x + nx * a, *w = ip->w + nx * a, *g = ip->g + nx * a, rho = nt->rho_nat[a];
    PetscReal        v[NX_MAX];
    v[0] = g[0] - rho * PetscRealPart(wy[nc * a]);
    if (nc == 2) {
      const PetscReal swt = rho * PetscRealPart(wy[2 * a + 1]);
      v[1]                = g[1] - swt;
      v[2]                = g[2] + swt;
      v[3]                = g[3];
    }
    ApplyKinv(ip, a, v, dx + nx * a);
    for (PetscInt i = 0; i < nx; i++) {
      const PetscReal t = target ? target[nx * a + i] : 0.0;
      dw[nx * a + i]    = (t - x[i] * w[i] - w[i] * dx[nx * a + i]) / x[i];
    }
  }
  PetscCall(VecRestoreArrayRead(nt->Wd, &wy));
  PetscFunctionReturn(0);
}

/* The longest step in [0, 1] that keeps x + t dx and w + t dw nonnegative, over all ranks. */
static PetscErrorCode LongestStep(KergsSolver s, const InteriorPoint *ip, const PetscReal *dx, const PetscReal *dw, PetscReal *step)
{
  PetscReal t = 1.0;

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < ip->n; a++) {
    if (!ip->in[a]) continue;
    for (PetscInt i = ip->nx * a; i < ip->nx * (a + 1); i++) {
      if (dx[i] < 0) t = PetscMin(t, -ip->x[i] / dx[i]);
      if (dw[i] < 0) t = PetscMin(t, -ip->w[i] / dw[i]);
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &t, 1, MPIU_REAL, MPIU_MIN, s->comm));
  *step = t;
  PetscFunctionReturn(0);
}

/* Mehrotra's centring: sigma = (gap after the predictor's longest step / gap)^3, and the corrector's target
   sigma gap - dxa dwa. */
static PetscErrorCode CorrectorTarget(KergsSolver s, InteriorPoint *ip, PetscReal gap, PetscReal step, PetscReal *target)
{
  PetscReal sum = 0.0, sigma;

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < ip->n; a++) {
    if (!ip->in[a]) continue;
    for (PetscInt i = ip->nx * a; i < ip->nx * (a + 1); i++) sum += (ip->x[i] + step * ip->dxa[i]) * (ip->w[i] + step * ip->dwa[i]);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, s->comm));
  /* Mehrotra's heuristic (Wright, Primal-Dual Interior-Point Methods, SIAM 1997, ch. 10), capped at 1: with M not
     monotone the predicted gap can exceed the current one */
  sigma = gap > 0 ? PetscMin(1.0, PetscPowReal(sum / (ip->nx * PetscMax(ip->nglobal, 1)) / gap, 3.0)) : 0.0;
  for (PetscInt i = 0; i < ip->nx * ip->n; i++) target[i] = sigma * gap - ip->dxa[i] * ip->dwa[i];
  PetscFunctionReturn(0);
}

/* The first point: every x the largest |c| (c = (rho v^d_n, rho v^d_t, -rho v^d_t, 0), or rho v^d_n without friction),
   w = max(M x + c, 0) + that. */
static PetscErrorCode FirstPoint(KergsSolver s, Newton *nt, InteriorPoint *ip, Vec r, Vec u, Vec vd)
{
  const PetscScalar *vl, *ul;
  PetscReal          scale = 0.0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(vd, &vl));
  for (PetscInt a = 0; a < ip->n; a++)
    if (ip->in[a])
      for (PetscInt c = 0; c < ip->nc; c++) scale = PetscMax(scale, nt->rho_nat[a] * PetscAbsScalar(vl[ip->nc * a + c]));
  PetscCall(VecRestoreArrayRead(vd, &vl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &scale, 1, MPIU_REAL, MPIU_MAX, s->comm));
  if (!(scale > 0)) scale = 1.0;
  for (PetscInt i = 0; i < ip->nx * ip->n; i++) ip->x[i] = scale;
  PetscCall(ImpulsesFromX(nt, ip, r, u, vd));
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < ip->n; a++) {
    PetscReal mx[NX_MAX];
    if (!ip->in[a]) continue;
    LCPMap(s, nt, ip, a, ip->x + ip->nx * a, ul, mx);
    for (PetscInt i = 0; i < ip->nx; i++) ip->w[ip->nx * a + i] = PetscMax(mx[i], 0.0) + scale;
  }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscFunctionReturn(0);
}

static PetscErrorCode Create(KergsSolver s, const Newton *nt, PetscInt n, PetscInt nc, InteriorPoint *ip)
{
  const PetscInt nx = nc == 2 ? NX_MAX : 1;
  PetscInt       m  = 0;

  PetscFunctionBeginUser;
  PetscCheck(nc == 1 || nc == 2, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "interior-point start: %" PetscInt_FMT " components per contact, not 1 or 2", nc);
  ip->n  = n;
  ip->nc = nc;
  ip->nx = nx;
  PetscCall(PetscMalloc1(n + 1, &ip->in));
  for (PetscInt a = 0; a < n; a++) {
    ip->in[a] = (PetscBool)(s->active[a] && (!nt->working_set || nt->in_J[a]));
    if (ip->in[a]) m++;
  }
  PetscCall(MPIU_Allreduce(&m, &ip->nglobal, 1, MPIU_INT, MPI_SUM, s->comm));
  PetscCall(PetscCalloc5(nx * n + 1, &ip->x, nx * n + 1, &ip->w, nx * n + 1, &ip->f1, nx * nx * n + 1, &ip->Kinv, nx * n + 1, &ip->g));
  PetscCall(PetscCalloc5(nx * n + 1, &ip->dxa, nx * n + 1, &ip->dwa, nx * n + 1, &ip->dx, nx * n + 1, &ip->dw, nx * n + 1, &ip->target));
  PetscFunctionReturn(0);
}

static PetscErrorCode Destroy(InteriorPoint *ip)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree5(ip->x, ip->w, ip->f1, ip->Kinv, ip->g));
  PetscCall(PetscFree5(ip->dxa, ip->dwa, ip->dx, ip->dw, ip->target));
  PetscCall(PetscFree(ip->in));
  PetscCall(KSPDestroy(&ip->ksp));
  PetscFunctionReturn(0);
}

/* One predictor-corrector iteration; *ok false when a K is singular, a linear solve failed or the step vanished. */
static PetscErrorCode Iterate(KergsSolver s, Newton *nt, InteriorPoint *ip, PetscReal gap, PetscBool *ok)
{
  PetscInt  good;
  PetscReal step;
  PetscBool solved;

  PetscFunctionBeginUser;
  good = SetBlocks(s, nt, ip) ? 1 : 0;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &good, 1, MPIU_INT, MPI_MIN, s->comm));
  *ok = (PetscBool)good;
  if (!*ok) PetscFunctionReturn(0);
  PetscCall(NewtonAssembleJacobian(s, nt, ip->n, ip->nc, nt->shift, 0.0));
  PetscCall(Direction(nt, ip, NULL, ip->dxa, ip->dwa, &solved));
  if (!solved) {
    *ok = PETSC_FALSE;
    PetscFunctionReturn(0);
  }
  PetscCall(LongestStep(s, ip, ip->dxa, ip->dwa, &step));
  PetscCall(CorrectorTarget(s, ip, gap, step, ip->target));
  PetscCall(Direction(nt, ip, ip->target, ip->dx, ip->dw, &solved));
  if (!solved) {
    *ok = PETSC_FALSE;
    PetscFunctionReturn(0);
  }
  PetscCall(LongestStep(s, ip, ip->dx, ip->dw, &step));
  step = PetscMin(1.0, 0.995 * step); /* the usual fraction to the boundary (Wright, ch. 10) */
  for (PetscInt i = 0; i < ip->nx * ip->n; i++) {
    ip->x[i] += step * ip->dx[i];
    ip->w[i] += step * ip->dw[i];
  }
  *ok = (PetscBool)(step > 0);
  PetscFunctionReturn(0);
}

/* The interior point's answer carries a small impulse on every contact of its problem, open ones included, and newton's
   working set leaves out of J only contacts without one (newton_working.c): measured on the 300-disk rest step, when
   every contact was in the problem, none left out against 148 without the start. So contacts whose normal pair leans open (rho u_n > r_n)
   lose their impulse, kept if the natural residual at most doubles (measured: it grows by about 5 %). r, u, *res and nt->enorm updated. */
static PetscErrorCode DropOpenImpulses(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscReal *res)
{
  const PetscScalar *rl, *ul;
  PetscScalar       *tl;
  PetscReal          now;
  PetscInt           dropped = 0;

  PetscFunctionBeginUser;
  PetscCall(VecCopy(r, nt->rtry));
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  PetscCall(VecGetArray(nt->rtry, &tl));
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a] && nt->rho_nat[a] * PetscRealPart(ul[nc * a]) > PetscRealPart(rl[nc * a])) {
      for (PetscInt c = 0; c < nc; c++) tl[nc * a + c] = 0.0;
      dropped++;
    }
  PetscCall(VecRestoreArray(nt->rtry, &tl));
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MatMultAdd(nt->Wfull, nt->rtry, vd, nt->utry));
  PetscCall(NewtonNaturalResidual(s, nt, n, nc, nt->rtry, nt->utry, &now));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &dropped, 1, MPIU_INT, MPI_SUM, s->comm));
  PetscCall(PetscInfo(NULL, "interior point: %" PetscInt_FMT " open contacts' impulses dropped, natural residual %g -> %g%s\n", dropped,
                      (double)*res, (double)now, now <= 2.0 * *res ? "" : " (not kept)"));
  if (now <= 2.0 * *res) {
    PetscCall(VecCopy(nt->rtry, r));
    PetscCall(VecCopy(nt->utry, u));
    *res = now;
  } else
    PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, res)); /* nt->enorm of r itself, not of the trial */
  PetscFunctionReturn(0);
}

/* newton's linear-solve statistics (jacobians, factorizations, ...) count Newton's own steps; the start's linear work
   is in ip_seconds. Saved before the start and put back after it. */
typedef struct {
  PetscInt  jacobians, factorizations, reused, linear_its, failed_linear;
  PetscReal linear_seconds;
} LinearFigures;

static void SaveLinearFigures(const Newton *nt, LinearFigures *f)
{
  f->jacobians      = nt->jacobians;
  f->factorizations = nt->factorizations;
  f->reused         = nt->reused;
  f->linear_its     = nt->linear_its;
  f->failed_linear  = nt->failed_linear;
  f->linear_seconds = nt->linear_seconds;
}

static void RestoreLinearFigures(Newton *nt, const LinearFigures *f)
{
  nt->jacobians      = f->jacobians;
  nt->factorizations = f->factorizations;
  nt->reused         = f->reused;
  nt->linear_its     = f->linear_its;
  nt->failed_linear  = f->failed_linear;
  nt->linear_seconds = f->linear_seconds;
}

/* The start's own direct solver for J, or NULL where it uses newton's (its LU on one rank, or its gathered LU).
   With friction, where newton's KSP is a Krylov method (GMRES with additive Schwarz on several ranks above
   -solver_newton_redundant_max rows, or a method chosen by option), MUMPS's LU: the interior point's directions must be
   accurate, and J's scales spread as X^-1 W does. Measured on the 300-disk rest step on 2 ranks with additive Schwarz:
   at GMRES's rtol 1e-3 the iterates turned back after 5 iterations; at 1e-10 GMRES needed 7 iterations at the first and
   700 at the tenth, reached its cap, and Newton then needed 37 steps instead of 5.
   Without friction J = w / (rho x) + W is symmetric positive definite (SetBlocks), so always a symmetric factorization:
   CHOLMOD's Cholesky on one rank, MUMPS's LDL^T on several. Measured on the 40,000-disk frictionless rest step, one rank: the start's 16
   iterations took 5.2 s by CHOLMOD against 16.1 s by newton's LU.
   MUMPS orders by AMD (ICNTL(7) = 0): on the 100,000-disk frictionless rest step, 2 ranks, the start's 20 symmetric
   factorizations took 24 s by AMD, 25 s by AMF, 28 s by QAMD, 43 s by PORD and by METIS (MUMPS's own choice there);
   with friction, the 5,000-disk rest step's 30 LU factorizations 3.0 s against 3.3 s.
   Options under -solver_newton_ip_ (-solver_newton_ip_pc_factor_mat_solver_type, MUMPS's -solver_newton_ip_mat_mumps_icntl_*).
   Created again whenever J's rows change. */
static PetscErrorCode CreateDirectSolver(KergsSolver s, Newton *nt, PetscInt nc, KSP *ksp)
{
  PetscBool     direct, mumps;
  PetscMPIInt   size;
  PC            pc;
  MatSolverType package;

  PetscFunctionBeginUser;
  *ksp = NULL;
  PetscCall(PetscObjectTypeCompare((PetscObject)nt->ksp, KSPPREONLY, &direct));
  if (nc == 2 && direct) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(NewtonInteriorPointCreateKSP(s, nc, ksp));
  PetscCall(KSPSetOperators(*ksp, nt->J, nt->J));
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCFactorSetMatSolverType(pc, nc == 1 && size == 1 ? MATSOLVERCHOLMOD : MATSOLVERMUMPS));
  PetscCall(KSPSetFromOptions(*ksp)); /* first, so that the factor takes the prefix for its own options */
  PetscCall(PCFactorSetUpMatSolverType(pc));
  PetscCall(PCFactorGetMatSolverType(pc, &package)); /* the option's, if given */
  PetscCall(PetscStrcmp(package, MATSOLVERMUMPS, &mumps));
  if (mumps) {
    Mat F;
    PetscCall(PCFactorGetMatrix(pc, &F));
    /* AMD: MUMPS's own choice took 1.8 times as long (above); -solver_newton_ip_mat_mumps_icntl_7, applied after this
       value at the symbolic factorization, still wins */
    PetscCall(MatMumpsSetIcntl(F, 7, 0));
  }
  PetscFunctionReturn(0);
}

/* The start's own KSP, without operators: options prefix -solver_newton_ip_, a direct solve (LU with friction,
   Cholesky without). Also called once at newton's set-up so that -help lists its options and the unused-option check
   knows them. */
PetscErrorCode NewtonInteriorPointCreateKSP(KergsSolver s, PetscInt nc, KSP *ksp)
{
  PC   pc;
  char prefix[256];

  PetscFunctionBeginUser;
  PetscCall(KergsSolverInnerPrefix(s, "solver_newton_ip_", prefix, sizeof(prefix)));
  PetscCall(KSPCreate(s->comm, ksp));
  PetscCall(KSPSetOptionsPrefix(*ksp, prefix));
  PetscCall(KSPSetType(*ksp, KSPPREONLY));
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCSetType(pc, nc == 2 ? PCLU : PCCHOLESKY));
  PetscFunctionReturn(0);
}

/* The contacts left out of the problem that r closes (u_n < 0 at u = W r + v^d) join it, every component of their x
   and w set to sqrt(gap) (gap: the iteration's mean x.w: on the central path's scale), and J and the start's direct
   solver are set up again on J's new rows (J's size may also change newton's choice of solver); *added on every rank.
   Measured: starting them at the larger of that and rho |u_n| (the impulse that would stop the contact) took the
   1,200-disk rest step from 5 Newton steps after the start to 28, and the 500-disk pressure scene at dt 5.5e-3 from
   5.0 s to 7.2 s with a step unconverged. */
static PetscErrorCode JoinClosingContacts(KergsSolver s, Newton *nt, InteriorPoint *ip, Vec u, PetscReal gap, PetscInt *added)
{
  const PetscScalar *ul;
  PetscInt           count = 0;

  PetscFunctionBeginUser;
  *added = 0;
  if (!nt->working_set) PetscFunctionReturn(0);
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < ip->n; a++)
    if (s->active[a] && !ip->in[a] && PetscRealPart(ul[ip->nc * a]) < 0) {
      const PetscReal start = PetscSqrtReal(gap);
      ip->in[a] = nt->in_J[a] = PETSC_TRUE;
      for (PetscInt i = ip->nx * a; i < ip->nx * (a + 1); i++) ip->x[i] = ip->w[i] = start;
      count++;
    }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(MPIU_Allreduce(&count, added, 1, MPIU_INT, MPI_SUM, s->comm));
  if (!*added) PetscFunctionReturn(0);
  ip->nglobal += *added;
  PetscCall(PetscInfo(NULL, "interior point: %" PetscInt_FMT " contacts left out are closing: they join the problem\n", *added));
  PetscCall(NewtonDestroyJacobian(nt));
  PetscCall(NewtonSetUpJacobian(s, nt, ip->n, ip->nc));
  PetscCall(KSPDestroy(&ip->ksp));
  PetscCall(CreateDirectSolver(s, nt, ip->nc, &ip->ksp));
  PetscFunctionReturn(0);
}

/* Interior-point iterations from the first point, at most -solver_newton_ip_max_it, until the natural residual is at
   most `target`; *best and nt->rbest hold the best r by natural residual over the entry and every iterate. An iterate
   that brings contacts into the problem restarts the rules that watch the residual's growth (its residual counts the
   contacts it closes while they were left out). */
static PetscErrorCode Iterations(KergsSolver s, Newton *nt, InteriorPoint *ip, Vec r, Vec u, Vec vd, PetscReal target, PetscReal *best)
{
  PetscReal ip_best    = PETSC_MAX_REAL; /* over these iterates */
  PetscInt  since_best = 0;              /* iterations since ip_best last fell */

  PetscFunctionBeginUser;
  PetscCall(FirstPoint(s, nt, ip, r, u, vd));
  for (PetscInt k = 0;; k++) {
    PetscReal now, gap = 0.0;
    PetscBool ok    = PETSC_FALSE;
    PetscInt  added = 0;
    PetscCall(NewtonNaturalResidual(s, nt, ip->n, ip->nc, r, u, &now));
    PetscCall(PetscInfo(NULL, "interior point %" PetscInt_FMT ": natural residual %g\n", k, (double)now));
    if (now < *best) {
      *best = now;
      PetscCall(VecCopy(r, nt->rbest));
    }
    if (!(now < PETSC_MAX_REAL) || *best <= target || k >= nt->ip_max_it) break;
    PetscCall(Residuals(s, nt, ip, u, &gap));
    PetscCall(JoinClosingContacts(s, nt, ip, u, gap, &added));
    if (added) {
      PetscCall(ImpulsesFromX(nt, ip, r, u, vd));
      PetscCall(Residuals(s, nt, ip, u, &gap));
      ip_best    = PETSC_MAX_REAL; /* another problem */
      since_best = 0;
    } else {
      since_best = now < ip_best ? 0 : since_best + 1;
      ip_best    = PetscMin(ip_best, now);
      /* measured: once the iterates leave the central path (M + X^-1 W grows nearly singular on a few contacts, whose
         directions block the step; or a Krylov solve is too loose) the residual grows without coming back */
      if (now > 10.0 * ip_best || since_best >= 5) break;
    }
    PetscCall(Iterate(s, nt, ip, gap, &ok));
    if (!ok) break;
    nt->ip_its++;
    PetscCall(ImpulsesFromX(nt, ip, r, u, vd));
  }
  PetscFunctionReturn(0);
}

/* From r (u = W r + v^d and *res its natural residual on entry): interior-point iterations until the natural residual
   of r = T x is at most max(-solver_newton_ip_tol, -solver_tol), or -solver_tol without friction when
   -solver_newton_ip_tol is not given (the normal impulses' LCP is sufficient and the iterations get there: on the
   frictionless rest step of 10,000, 40,000 and 100,000 disks, one rank, 0.89, 0.92 and 0.74 of the time with the
   frictional default 1e-5, and 3 Newton steps after the start instead of 6 to 8); r and u end at the best answer by natural residual
   (the entry's if none improved on it). With newton's working set the problem leaves out the
   contacts that the warm start leaves open (newton_working.c), J is set up on the others here and released after:
   measured on the 500-disk pressure scene at dt 5.5e-3, two thirds of the 2,700 contacts within the alert distance are
   open, and with them in J an iteration took up to 140 ms against 4 ms without. An iterate that closes some of them
   brings them into the problem (JoinClosingContacts). */
PetscErrorCode NewtonInteriorPointStart(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscReal *res)
{
  InteriorPoint   ip = {0};
  LinearFigures   counted;
  PetscReal       best   = *res;
  const PetscReal target = nc == 1 && !nt->ip_tol_set ? s->tol : PetscMax(nt->ip_tol, s->tol);
  PetscLogDouble  t0, t1;
  const PetscBool presort = nt->presort;

  PetscFunctionBeginUser;
  if (*res <= target || nt->ip_max_it <= 0) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KERGS_InteriorPoint, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  SaveLinearFigures(nt, &counted);
  PetscCall(VecCopy(r, nt->rbest));
  /* Without friction the start's Cholesky orders J itself: the AMD presorting of newton's own LU (one rank, with
     -solver_newton_cholesky 0: else J is not presorted anyway) would be computed for nothing at every set-up of J, 12
     of them on the 100,000-disk frictionless rest step (3.3 of 45 s) */
  if (nc == 1) nt->presort = PETSC_FALSE;
  if (nt->working_set) {
    PetscCall(NewtonWorkingSetBegin(s, nt, n, nc, r, u));
    PetscCall(NewtonSetUpJacobian(s, nt, n, nc));
  }
  PetscCall(Create(s, nt, n, nc, &ip));
  PetscCall(CreateDirectSolver(s, nt, nc, &ip.ksp));
  PetscCall(Iterations(s, nt, &ip, r, u, vd, target, &best));
  nt->ip_answer = (PetscBool)(best < *res); /* else r goes back to the entry's */
  PetscCall(Destroy(&ip));
  PetscCall(VecCopy(nt->rbest, r));
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, res));
  if (nt->ip_its > 0) PetscCall(DropOpenImpulses(s, nt, n, nc, r, u, vd, res));
  RestoreLinearFigures(nt, &counted);
  if (nt->working_set) PetscCall(NewtonDestroyJacobian(nt));
  nt->presort = presort;
  PetscCall(PetscTime(&t1));
  nt->ip_seconds += t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_InteriorPoint, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
