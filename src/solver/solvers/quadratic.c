/* The convex QPs that solver types hand to a Tao (tresca's Tresca problems, newton's De Saxce start):
   f(x) = 1/2 x^T H x + c^T x, its gradient H x + c, and its constant Hessian H (solverimpl.h, KergsQuadratic). */
#include <kergs/private/solverimpl.h>

static PetscErrorCode QuadraticObjectiveGradient(Tao tao, Vec x, PetscReal *f, Vec g, void *ctx)
{
  KergsQuadratic *q = (KergsQuadratic *)ctx;
  PetscScalar     xHx, cx;

  PetscFunctionBeginUser;
  (void)tao;
  PetscCall(MatMult(q->H, x, g));
  PetscCall(VecDot(x, g, &xHx));
  PetscCall(VecDot(q->c, x, &cx));
  PetscCall(VecAXPY(g, 1.0, q->c));
  *f = 0.5 * PetscRealPart(xHx) + PetscRealPart(cx);
  PetscFunctionReturn(0);
}

/* The Hessian is H as assembled: nothing to compute. */
static PetscErrorCode QuadraticHessian(Tao tao, Vec x, Mat H, Mat P, void *ctx)
{
  PetscFunctionBeginUser;
  (void)tao;
  (void)x;
  (void)H;
  (void)P;
  (void)ctx;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsQuadraticSetTao(KergsQuadratic *q, Tao tao)
{
  PetscFunctionBeginUser;
  /* no gradient vector of ours: with one, TRON (PETSc 3.18) kept a reference to it past TaoDestroy, a vector leaked
     per step (-malloc_dump, tests/memcheck.cmake); Tao makes its own */
  PetscCall(TaoSetObjectiveAndGradient(tao, NULL, QuadraticObjectiveGradient, q));
  PetscCall(TaoSetHessian(tao, q->H, q->H, QuadraticHessian, q));
  PetscFunctionReturn(0);
}
