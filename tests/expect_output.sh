#!/usr/bin/env bash
# Usage: expect_output.sh ITEM... -- command [args...]
#        expect_output.sh --self-check
# Passes when the command exits 0, did not die of a signal, and prints, in the order given, one line for each ITEM:
#   -name  the option's own help line, as PETSc prints it: "  -name <value...", "  -name: <TRUE...>" (a flag) or
#          "  -name ascii[..." (a viewer). A name quoted in another option's text does not count.
#   text   a line that starts with this extended regular expression (a heading, a line of a view).
# ctest's PASS_REGULAR_EXPRESSION ignores the exit status, and a pipe into grep reads only grep's: this script reads both.
# --self-check runs the script on stand-in commands that must fail (non-zero exit, missing option, option quoted only
# in another's text, wrong order) and one that must pass.

line_pattern() {
  case "$1" in
    -*) printf '^  %s(: <| <| ascii\\[)' "$1" ;;
    *) printf '^%s' "$1" ;;
  esac
}

expect_output() {
  local items=() out rc i=0 line
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do items+=("$1"); shift; done
  [ "$1" = "--" ] && [ $# -ge 2 ] || { echo "usage: expect_output.sh ITEM... -- command [args...]"; return 2; }
  shift
  out=$("$@" 2>&1); rc=$?
  if [ $rc -ne 0 ]; then echo "$out" | tail -n 25; echo "FAIL: exit code $rc, 0 expected"; return 1; fi
  while IFS= read -r line && [ $i -lt ${#items[@]} ]; do
    [[ $line =~ $(line_pattern "${items[$i]}") ]] && i=$((i + 1))
  done <<< "$out"
  if [ $i -lt ${#items[@]} ]; then
    echo "FAIL: no line /$(line_pattern "${items[$i]}")/ after the line of ${items[$((i > 0 ? i - 1 : 0))]}"
    return 1
  fi
  echo "PASS: exit code 0 and the ${#items[@]} expected lines, in order"
}

self_check() {
  local help='Scene options:
  -dt <0.001 : 0.001>: Time step, see also -steps (None)
  -quiet: <FALSE : FALSE> No step lines (None)
  -solver_monitor ascii[:[filename]]: Prints object (PetscOptionsGetViewer)'
  local status=0
  run() { # expected-status description items... -- command
    local want=$1 what=$2 got
    shift 2
    expect_output "$@" > /dev/null; got=$?
    if [ $got -eq "$want" ]; then echo "self-check: $what: status $got, as expected"; else echo "self-check FAILED: $what: status $got, $want expected"; status=1; fi
  }
  run 0 "all present" 'Scene options' -dt -quiet -solver_monitor -- printf '%s\n' "$help"
  run 1 "non-zero exit" -dt -- sh -c 'printf "%s\n" "$0"; exit 3' "$help"
  run 1 "option missing" -dt -theta -- printf '%s\n' "$help"
  run 1 "option only in another's text" -steps -- printf '%s\n' "$help"
  run 1 "wrong order" -quiet -dt -- printf '%s\n' "$help"
  return $status
}

if [ "$1" = "--self-check" ]; then self_check; else expect_output "$@"; fi
