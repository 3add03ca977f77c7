#!/usr/bin/env bash
# Source-level rules of the freestanding core (include/ and src/), complementing the
# link-level symbol check on the target:
#   - no floating point types, no heap (malloc/new/delete), no exceptions or RTTI;
#   - only the compiler's freestanding headers and the project's own headers are included.
# Usage: check-core-rules.sh <dir-or-file>...   (exit 1 and the offending lines on violation)
set -u
status=0
count=0
for dir in "$@"; do
  while IFS= read -r -d '' file; do
    count=$((count + 1))
    # Strip // comments and string literals so prose like "double-precision" is not flagged.
    hits=$(sed -e 's://.*$::' -e 's/"[^"]*"/""/g' "$file" | grep -nE \
      '\b(float|double)\b|\b(malloc|calloc|realloc|free)[[:space:]]*\(|\bnew[[:space:]]+[A-Za-z_:]|\bdelete\b|\bthrow\b|\btry[[:space:]]*\{|\bcatch[[:space:]]*\(|\bdynamic_cast\b|\btypeid\b' \
      | grep -vE '=[[:space:]]*delete' || true)
    includes=$(grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*<' "$file" \
      | grep -vE '<(stdint|stddef|stdarg|limits|stdbool)\.h>' || true)
    if [ -n "$hits$includes" ]; then
      status=1
      printf '%s\n' "$hits" "$includes" | sed -e '/^$/d' -e "s|^|$file:|"
    fi
  done < <(find "$dir" -type f \( -name '*.h' -o -name '*.cpp' \) -print0)
done
if [ "$status" -ne 0 ]; then
  echo "FAIL: the lines above break the freestanding-core rules (docs/architecture.md)" >&2
else
  echo "PASS: $count core files follow the freestanding rules"
fi
exit "$status"
