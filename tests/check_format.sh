#!/bin/sh
# Every C source and header of the project is formatted by the committed .clang-format (Debian's clang-format,
# installed by scripts/setup.sh). Fix with: clang-format -i $(git ls-files '*.c' '*.h')
cd "$(dirname "$0")/.." || exit 2
command -v clang-format >/dev/null || { echo "format: clang-format is not installed (scripts/setup.sh installs it)"; exit 1; }
files=$(git ls-files '*.c' '*.h' 2>/dev/null || find src include tests -name '*.c' -o -name '*.h')
clang-format --dry-run --Werror $files || { echo "format: the files above differ from .clang-format; run clang-format -i on them"; exit 1; }
echo "format: every file follows .clang-format"
