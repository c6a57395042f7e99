#!/usr/bin/env bash
# deb_test.sh BUILD_DIR OUT_DIR          makes the .deb (cpack) in OUT_DIR and checks it
# deb_test.sh --install OUT_DIR VERSION  installs it with apt-get, runs the default scenario, removes it
# The first: organsim_<version>_<arch>.deb whose Depends (dpkg-shlibdeps)
# names no -dev package, holding the binary, the scenarios and the man page.
# The second needs root (CI's job); elsewhere it exits 77 (skipped). It puts
# the machine back as it was: it removes exactly the packages it installed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd -P)

if [ "$1" != --install ]; then
  build=$1 out=$2
  rm -rf "$out" && mkdir -p "$out"
  (cd "$build" && cpack -G DEB -B "$out" >"$out/cpack.log" 2>&1) || { tail -n 30 "$out/cpack.log"; exit 1; }
  debs=("$out"/organsim_*_*.deb)
  [ ${#debs[@]} -eq 1 ] && [ -f "${debs[0]}" ] || { echo "FAIL: no single organsim_<version>_<arch>.deb in $out"; ls "$out"; exit 1; }
  deb=${debs[0]}
  arch=$(dpkg --print-architecture)
  case $(basename "$deb") in
    organsim_*_"$arch".deb) ;;
    *) echo "FAIL: $(basename "$deb") is not organsim_<version>_$arch.deb"; exit 1 ;;
  esac
  dpkg-deb --info "$deb" | tee "$out/info.txt"
  depends=$(dpkg-deb --field "$deb" Depends)
  [ -n "$depends" ] || { echo "FAIL: no Depends"; exit 1; }
  names=$(tr ',|' '\n\n' <<<"$depends" | awk 'NF {print $1}')
  # Libraries the binary links, by their runtime packages.
  for lib in libc6 libstdc++6 libgomp1 libhwy1 libopencv-core406 libopencv-videoio406 libegl1 libopenigtlink1.11; do
    grep -qxF "$lib" <<<"$names" || { echo "FAIL: Depends lacks $lib: $depends"; exit 1; }
  done
  if grep -E -- '-dev$' <<<"$names"; then
    echo "FAIL: Depends names a -dev package: $depends"; exit 1
  fi
  dpkg-deb --contents "$deb" >"$out/contents.txt"
  for f in ./usr/bin/organsim ./usr/share/organsim/scenarios/default.json ./usr/share/organsim/examples/liver.off \
           ./usr/share/man/man1/organsim.1.gz ./usr/share/doc/organsim/README.md; do
    grep -qE " $f\$" "$out/contents.txt" || { echo "FAIL: $f not in the package"; cat "$out/contents.txt"; exit 1; }
  done
  echo "ok: $(basename "$deb")"
  exit 0
fi

out=$2 version=$3
if [ "$(id -u)" -ne 0 ]; then
  echo "SKIP: installing the .deb with apt-get needs root (CI runs this as root)"
  exit 77
fi
if dpkg-query -W -f='${Status}' organsim 2>/dev/null | grep -q "install ok installed"; then
  echo "SKIP: an organsim package is already installed here; not replacing it"
  exit 77
fi
debs=("$out"/organsim_*_*.deb)
[ -f "${debs[0]}" ] || { echo "FAIL: no .deb in $out (the Package.Deb test makes it)"; exit 1; }
before=$(mktemp) after=$(mktemp) work=$(mktemp -d /tmp/organsim-deb-test.XXXXXX)
dpkg-query -W -f='${Package}:${Architecture} ${Status}\n' | awk '$NF == "installed" {print $1}' | sort >"$before"
restore() {
  dpkg-query -W -f='${Package}:${Architecture} ${Status}\n' | awk '$NF == "installed" {print $1}' | sort >"$after"
  added=$(comm -13 "$before" "$after" | tr '\n' ' ')
  if [ -n "$added" ]; then
    echo "removing what the test installed: $added"
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive apt-get purge -y -qq $added >/dev/null
  fi
  rm -rf "$before" "$after" "$work"
}
trap restore EXIT
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${debs[0]}" >"$work/apt.log" 2>&1 ||
  { tail -n 30 "$work/apt.log"; exit 1; }
[ "$(command -v organsim)" = /usr/bin/organsim ] || { echo "FAIL: organsim is not /usr/bin/organsim"; exit 1; }
/usr/bin/organsim --version
man_page=$(man -w organsim 2>/dev/null || echo /usr/share/man/man1/organsim.1.gz)
zcat "$man_page" | grep -q '^\.SS run$' || { echo "FAIL: the man page has no run section"; exit 1; }
cd "$work"
/usr/bin/organsim run /usr/share/organsim/scenarios/default.json --threads 1 >run.log 2>&1 ||
  { echo "FAIL: organsim run failed:"; tail -n 30 run.log; exit 1; }
tail -n 3 run.log
python3 "$here/check_force_log.py" out/default/forces.json "$version"
