#!/usr/bin/env bash
# setup.sh [--tests] [--list]
# Installs the Debian 12 packages organsim needs: scripts/packages/demo.txt
# (build and run the executable: what scripts/demo.sh needs), and with
# --tests also scripts/packages/tests.txt (what only the tests use; what
# scripts/test.sh asks for). Idempotent: packages already present are
# skipped, so it is cheap to re-run. --list prints the packages, one a
# line, and installs nothing.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)

lists=("$here/packages/demo.txt")
list_only=0
for arg in "$@"; do
  case $arg in
    --tests) lists+=("$here/packages/tests.txt") ;;
    --list) list_only=1 ;;
    *) echo "usage: setup.sh [--tests] [--list]" >&2; exit 2 ;;
  esac
done

packages=()
for list in "${lists[@]}"; do
  while read -r p _; do
    case $p in ''|'#'*) continue ;; esac
    packages+=("$p")
  done <"$list"
done

if [ $list_only = 1 ]; then
  printf '%s\n' "${packages[@]}"
  exit 0
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
