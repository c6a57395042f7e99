#!/usr/bin/env bash
# The layer order of organsim's sources (docs/architecture.md "Layers"): a
# file may include headers of its own folder and of folders listed before
# it, never of a folder after it. Prints every include that runs upward and
# exits 1 if there is one. Run by ctest (Layers.IncludesRunDownwardOnly).
set -euo pipefail
root=$(cd "${1:-$(dirname "$0")/..}" && pwd)
cd "$root"

# Lowest first. core/<folder> by folder name; meshing/, igtl/ and app/ by their own.
layers=(util mesh physics model sim scenario stability topology io validation fit run sweep live gl render meshing igtl app)
declare -A rank
for i in "${!layers[@]}"; do rank[${layers[$i]}]=$i; done

# The layer of a path, a source file's or an include's: core/<folder>/...,
# meshing/..., igtl/..., app/...; "" for anything else.
layer_of() {
  case "$1" in
    core/*/*) echo "${1#core/}" | cut -d/ -f1 ;;
    meshing/*) echo meshing ;;
    igtl/*) echo igtl ;;
    app/*) echo app ;;
    *) echo "" ;;
  esac
}

status=0
checked=0
while IFS= read -r file; do
  from=$(layer_of "$file")
  [ -n "$from" ] || continue
  if [ -z "${rank[$from]+x}" ]; then
    echo "$file: folder '$from' has no place in the layer order (scripts/check_layers.sh)"
    status=1
    continue
  fi
  while IFS= read -r line; do
    include=$(sed -E 's/^[^"]*"([^"]+)".*/\1/' <<<"${line#*:}")
    to=$(layer_of "$include")
    [ -n "$to" ] || continue
    checked=$((checked + 1))
    if [ -z "${rank[$to]+x}" ]; then
      echo "$file:${line%%:*}: includes $include, whose folder '$to' has no place in the layer order"
      status=1
    elif [ "$to" != "$from" ] && [ "${rank[$to]}" -gt "${rank[$from]}" ]; then
      echo "$file:${line%%:*}: $from includes $include from the higher layer $to"
      status=1
    fi
  done < <(grep -n -E '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$file" || true)
done < <(find core meshing igtl app -type f \( -name '*.h' -o -name '*.cpp' \) | sort)

if [ "$status" -eq 0 ]; then
  echo "layers: $checked includes between project folders, all downward (${layers[*]})"
fi
exit "$status"
