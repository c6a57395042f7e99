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

# The layer of a path, a source file's or an include's, into $layer:
# core/<folder>/..., meshing/..., igtl/..., app/...; "" for anything else.
# Built-ins only: a subprocess per include made this check take half a minute.
layer_of() {
  case "$1" in
    core/*/*) layer=${1#core/}; layer=${layer%%/*} ;;
    meshing/*) layer=meshing ;;
    igtl/*) layer=igtl ;;
    app/*) layer=app ;;
    *) layer="" ;;
  esac
}

status=0
checked=0
include_line='^[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]+)"'
while IFS= read -r file; do
  layer_of "$file"
  from=$layer
  [ -n "$from" ] || continue
  if [ -z "${rank[$from]+x}" ]; then
    echo "$file: folder '$from' has no place in the layer order (scripts/check_layers.sh)"
    status=1
    continue
  fi
  number=0
  while IFS= read -r line || [ -n "$line" ]; do
    number=$((number + 1))
    [[ $line =~ $include_line ]] || continue
    include=${BASH_REMATCH[1]}
    layer_of "$include"
    to=$layer
    [ -n "$to" ] || continue
    checked=$((checked + 1))
    if [ -z "${rank[$to]+x}" ]; then
      echo "$file:$number: includes $include, whose folder '$to' has no place in the layer order"
      status=1
    elif [ "$to" != "$from" ] && [ "${rank[$to]}" -gt "${rank[$from]}" ]; then
      echo "$file:$number: $from includes $include from the higher layer $to"
      status=1
    fi
  done <"$file"
done < <(find core meshing igtl app -type f \( -name '*.h' -o -name '*.cpp' \) | sort)

if [ "$status" -eq 0 ]; then
  echo "layers: $checked includes between project folders, all downward (${layers[*]})"
fi
exit "$status"
