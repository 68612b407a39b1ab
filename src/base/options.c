/* kergs options readers: lists of numbers and names whose length the options database decides, points and boxes of a
   fixed number of values, read inside a component's PetscOptionsBegin/End block so that -help lists them; and the check
   of integer options against this build's PetscInt, after they were read (include/kergs/base.h). */
#include <kergs/base.h>
#include <stdlib.h>
#include <string.h>

/* Number of comma-separated values given to option opt (under the block's prefix), 0 when absent. */
static PetscErrorCode OptionsCountValues(PetscOptionItems *PetscOptionsObject, const char opt[], PetscInt *count)
{
  const char *value;
  PetscBool   found;

  PetscFunctionBeginUser;
  *count = 0;
  PetscCall(PetscOptionsFindPair(PetscOptionsObject->options, PetscOptionsObject->prefix, opt, &value, &found));
  if (!found || !value || !value[0]) PetscFunctionReturn(0);
  *count = 1;
  for (const char *c = value; *c; c++)
    if (*c == ',') (*count)++;
  PetscFunctionReturn(0);
}

/* Room for a list option: *values (size bytes an entry, zeroed) holds every value given to opt and one more, so that it
   is never NULL (the help printer reads values[0]); *n its capacity, as PETSc's array readers take it. */
static PetscErrorCode OptionsListAlloc(PetscOptionItems *PetscOptionsObject, const char opt[], size_t size, void *values, PetscInt *n)
{
  PetscInt cap;

  PetscFunctionBeginUser;
  PetscCall(OptionsCountValues(PetscOptionsObject, opt, &cap));
  PetscCall(PetscCalloc(size * (size_t)(cap + 1), values));
  *n = cap + 1;
  PetscFunctionReturn(0);
}

/* After the read: *n the number of values given, 0 when the option is absent. */
static void OptionsListRead(PetscBool found, PetscInt *n, PetscBool *set)
{
  if (!found) *n = 0;
  if (set) *set = found;
}

/* Read a list of reals of any length into a new array (*values, free with PetscFree). */
PetscErrorCode KergsOptionsRealList(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], PetscInt *n,
                                    PetscReal **values, PetscBool *set)
{
  PetscBool found;

  PetscFunctionBeginUser;
  PetscCall(OptionsListAlloc(PetscOptionsObject, opt, sizeof(**values), values, n));
  PetscCall(PetscOptionsRealArray(opt, text, NULL, *values, n, &found));
  OptionsListRead(found, n, set);
  PetscFunctionReturn(0);
}

/* Same for integers. */
PetscErrorCode KergsOptionsIntList(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], PetscInt *n,
                                   PetscInt **values, PetscBool *set)
{
  PetscBool found;

  PetscFunctionBeginUser;
  PetscCall(KergsOptionsCheckInt(PetscOptionsObject->comm, PetscOptionsObject->prefix, opt));
  PetscCall(OptionsListAlloc(PetscOptionsObject, opt, sizeof(**values), values, n));
  PetscCall(PetscOptionsIntArray(opt, text, NULL, *values, n, &found));
  OptionsListRead(found, n, set);
  PetscFunctionReturn(0);
}

/* Same for names (free with PetscStrNArrayDestroy(*n, values)). */
PetscErrorCode KergsOptionsStringList(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], PetscInt *n,
                                      char ***values, PetscBool *set)
{
  PetscBool found;

  PetscFunctionBeginUser;
  PetscCall(OptionsListAlloc(PetscOptionsObject, opt, sizeof(**values), values, n));
  PetscCall(PetscOptionsStringArray(opt, text, NULL, *values, n, &found));
  OptionsListRead(found, n, set);
  PetscFunctionReturn(0);
}

/* Read exactly n reals (a point, a vector, a box); v is left unchanged when the option is absent. */
PetscErrorCode KergsOptionsReals(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], PetscInt n, PetscReal v[],
                                 PetscBool *set)
{
  PetscReal *tmp;
  PetscInt   nread = n, given;
  PetscBool  flg;
  char       help[512];
  size_t     len;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(n, &tmp));
  PetscCall(PetscArraycpy(tmp, v, n));
  /* -help prints only the first value of an absent array option: show the whole default in the text */
  PetscCall(PetscSNPrintf(help, sizeof(help), "%s (default ", text));
  for (PetscInt k = 0; k < n; k++) {
    PetscCall(PetscStrlen(help, &len));
    PetscCall(PetscSNPrintf(help + len, sizeof(help) - len, "%g%s", (double)v[k], k + 1 < n ? "," : ")"));
  }
  PetscCall(PetscOptionsRealArray(opt, help, NULL, tmp, &nread, &flg));
  if (flg) {
    PetscCall(OptionsCountValues(PetscOptionsObject, opt, &given));
    PetscCheck(given == n, PetscOptionsObject->comm, PETSC_ERR_ARG_SIZ,
               "Option -%s%s needs %" PetscInt_FMT " comma-separated values, got %" PetscInt_FMT,
               PetscOptionsObject->prefix ? PetscOptionsObject->prefix : "", opt + 1, n, given);
    PetscCall(PetscArraycpy(v, tmp, n));
  }
  PetscCall(PetscFree(tmp));
  if (set) *set = flg;
  PetscFunctionReturn(0);
}

/* A point or vector: exactly KERGS_DIM reals. */
PetscErrorCode KergsOptionsVector(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], PetscReal v[], PetscBool *set)
{
  PetscFunctionBeginUser;
  PetscCall(KergsOptionsReals(PetscOptionsObject, opt, text, KERGS_DIM, v, set));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOptionsCheckInt(MPI_Comm comm, const char prefix[], const char name[])
{
  char      value[4096], *token, *save = NULL;
  PetscBool set;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetString(NULL, prefix, name, value, sizeof(value), &set));
  if (!set) PetscFunctionReturn(0);
  for (token = strtok_r(value, ",", &save); token; token = strtok_r(NULL, ",", &save)) {
    char  *end;
    double v = strtod(token, &end);
    if (end == token || *end) continue; /* not a number: PETSc's parser reports it */
    PetscCheck(v <= (double)PETSC_MAX_INT && v >= (double)PETSC_MIN_INT, comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Option -%s%s: %s is out of the range of this build's integers (PetscInt is %d-bit: at most %" PetscInt_FMT ")",
               prefix ? prefix : "", name + 1, token, (int)(8 * sizeof(PetscInt)), (PetscInt)PETSC_MAX_INT);
    /* PETSc reads integers in digits only ("Input string 1e3 has no integer value", naming no option) */
    if (!strncmp(token, "0x", 2) || !strncmp(token, "0X", 2) || !strpbrk(token, ".eE")) continue;
    PetscCheck(v == (double)(long long)v, comm, PETSC_ERR_ARG_WRONG, "Option -%s%s: %s is not an integer", prefix ? prefix : "", name + 1,
               token);
    SETERRQ(comm, PETSC_ERR_ARG_WRONG,
            "Option -%s%s: %s is not an integer in digits (PETSc reads no exponent or decimal point): write %.0f", prefix ? prefix : "",
            name + 1, token, v);
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOptionsInt(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], const char man[],
                               PetscInt current, PetscInt *value, PetscBool *set)
{
  PetscFunctionBeginUser;
  PetscCall(KergsOptionsCheckInt(PetscOptionsObject->comm, PetscOptionsObject->prefix, opt));
  PetscCall(PetscOptionsInt(opt, text, man, current, value, set));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOptionsCheckBool(MPI_Comm comm, const char prefix[], const char name[])
{
  static const char *const truth[] = {"true", "false", "yes", "no", "on", "off", "1", "0"};
  char                     given[256];
  PetscBool                found, known = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetString(NULL, prefix, name, given, sizeof(given), &found));
  if (!found || !given[0]) PetscFunctionReturn(0); /* absent, or given alone: true */
  for (size_t k = 0; k < sizeof(truth) / sizeof(truth[0]) && !known; k++) PetscCall(PetscStrcasecmp(given, truth[k], &known));
  PetscCheck(known, comm, PETSC_ERR_ARG_WRONG,
             "Option -%s%s: %s is not a truth value (true, false, yes, no, on, off, 1 or 0; the option alone means true)",
             prefix ? prefix : "", name + 1, given);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOptionsBool(PetscOptionItems *PetscOptionsObject, const char opt[], const char text[], const char man[],
                                PetscBool current, PetscBool *value, PetscBool *set)
{
  PetscFunctionBeginUser;
  PetscCall(KergsOptionsCheckBool(PetscOptionsObject->comm, PetscOptionsObject->prefix, opt));
  PetscCall(PetscOptionsBool(opt, text, man, current, value, set));
  PetscFunctionReturn(0);
}

static PetscBool IsOptionName(const char *t)
{
  return t[0] == '-' && ((t[1] >= 'a' && t[1] <= 'z') || (t[1] >= 'A' && t[1] <= 'Z')) ? PETSC_TRUE : PETSC_FALSE;
}

PetscErrorCode KergsOptionsTextWalk(const char text[], KergsOptionVisitor visit, void *ctx)
{
  char  *copy, *save = NULL, *tok, name[256] = "", value[4096] = "";
  size_t len;

  PetscFunctionBeginUser;
  PetscCall(PetscStrallocpy(text, &copy));
  for (tok = strtok_r(copy, " \t\n", &save);; tok = strtok_r(NULL, " \t\n", &save)) {
    if (!tok || IsOptionName(tok)) {
      if (name[0]) PetscCall((*visit)(name, value, ctx));
      if (!tok) break;
      PetscCall(PetscStrncpy(name, tok, sizeof(name)));
      value[0] = 0;
      continue;
    }
    PetscCall(PetscStrlen(value, &len));
    PetscCall(PetscSNPrintf(value + len, sizeof(value) - len, "%s%s", len ? " " : "", tok));
  }
  PetscCall(PetscFree(copy));
  PetscFunctionReturn(0);
}
