#!/usr/bin/env bash
# The project's C and C++ sources against its .clang-format, changing nothing:
# lists every file clang-format would change and fails if there is one.
# Usage: check-format.sh SOURCE_DIR [CLANG_FORMAT]   (ctest: FormatCheck)
set -euo pipefail
source_dir=$1
clang_format=${2:-clang-format-14}
cd "$source_dir"
files=()
if git rev-parse --git-dir >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files -- '*.cpp' '*.hpp' '*.c' '*.h')
fi
if [ ${#files[@]} -eq 0 ]; then
  # No git, or git refuses the tree (another owner): the same folders.
  mapfile -t files < <(find firmware drivers calib tests board toolchain \
    -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.c' -o -name '*.h' \) | sort)
fi
if [ ${#files[@]} -eq 0 ]; then
  echo "check-format: no sources found under $source_dir" >&2
  exit 1
fi
unformatted=()
for f in "${files[@]}"; do
  "$clang_format" --dry-run -Werror --style=file "$f" >/dev/null 2>&1 || unformatted+=("$f")
done
if [ ${#unformatted[@]} -ne 0 ]; then
  echo "check-format: ${#unformatted[@]} of ${#files[@]} files differ from .clang-format" \
       "(fix: $clang_format -i FILE):" >&2
  printf '  %s\n' "${unformatted[@]}" >&2
  exit 1
fi
echo "check-format: ${#files[@]} files match .clang-format"
