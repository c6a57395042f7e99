#!/usr/bin/env bash
# install_run_test.sh BUILD_DIR SOURCE_DIR VERSION
# `cmake --install` into a temporary prefix, then the installed organsim runs
# the installed scenarios/default.json from a working folder outside the
# source tree, with the build and source trees hidden (empty file systems
# mounted over them in a private mount namespace), and its force log is
# checked. Exit 77 (skipped) only where no mount namespace can be made.
set -euo pipefail
build=$(cd "$1" && pwd -P)
source=$(cd "$2" && pwd -P)
version=$3
here=$(cd "$(dirname "$0")" && pwd -P)
tmp=$(mktemp -d /tmp/organsim-install-test.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix

cmake --install "$build" --prefix "$prefix" >"$tmp/install.log"
for f in bin/organsim share/organsim/scenarios/default.json share/organsim/examples/liver.off \
         share/man/man1/organsim.1.gz share/doc/organsim/README.md; do
  [ -e "$prefix/$f" ] || { echo "FAIL: $f not installed"; cat "$tmp/install.log"; exit 1; }
done
# No run path into the build tree: the installed binary finds only system libraries.
if readelf -d "$prefix/bin/organsim" | grep -E 'R(UN)?PATH' | grep -F -e "$build" -e "$source"; then
  echo "FAIL: the installed binary's run path names the build or source tree"; exit 1
fi

if [ "$(id -u)" -eq 0 ]; then ns=(unshare -m); else ns=(unshare -r -m); fi
if ! "${ns[@]}" true 2>/dev/null; then
  echo "SKIP: no private mount namespace here (${ns[*]} fails), so the build tree cannot be hidden"
  exit 77
fi
mkdir "$tmp/work"
# Inside the namespace: hide the build folder, then the source folder (which
# may hold it), prove they are gone, and run from the working folder.
"${ns[@]}" bash -c '
  set -euo pipefail
  build=$1 source=$2 prefix=$3 work=$4
  mount --make-rprivate / 2>/dev/null || true
  mount -t tmpfs none "$build"
  mount -t tmpfs none "$source"
  if [ -e "$build/CMakeCache.txt" ] || [ -e "$source/scenarios/default.json" ]; then
    echo "FAIL: the build or source tree is still visible"; exit 1
  fi
  cd "$work"
  "$prefix/bin/organsim" --version
  "$prefix/bin/organsim" run "$prefix/share/organsim/scenarios/default.json" --threads 1 >run.log 2>&1 ||
    { echo "FAIL: the installed organsim run failed:"; tail -n 30 run.log; exit 1; }
' bash "$build" "$source" "$prefix" "$tmp/work"
tail -n 12 "$tmp/work/run.log"
python3 "$here/check_force_log.py" "$tmp/work/out/default/forces.json" "$version"
