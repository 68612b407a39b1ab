#!/usr/bin/env bash
# Usage: expect_error.sh REGEX command [args...]
# Passes when the command exits non-zero, prints a message matching REGEX (extended, case-insensitive),
# and did not die of a signal (a crash is not a clear error).
regex=$1; shift
out=$("$@" 2>&1); rc=$?
echo "$out" | tail -n 25
if [ $rc -eq 0 ]; then echo "FAIL: exit code 0, an error was expected"; exit 1; fi
if echo "$out" | grep -qiE "segmentation|signal [0-9]+|SIGSEGV|SIGABRT|core dumped|Caught signal"; then echo "FAIL: crashed (rc=$rc)"; exit 1; fi
if ! echo "$out" | grep -qiE -e "$regex"; then echo "FAIL: no message matching /$regex/"; exit 1; fi
echo "PASS: rc=$rc and the message names the problem (/$regex/)"
