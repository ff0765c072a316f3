#!/usr/bin/env bash
# Install the Debian packages analogue needs, only those missing (idempotent; needs root or sudo
# only when something is missing: nothing is run through apt when ngspice is already on PATH).
#   scripts/install-system.sh            ngspice + libngspice0 (simulation)
#   scripts/install-system.sh --test     also chromium (the report page is loaded headless in tests)
set -euo pipefail
pkgs=()
# An ngspice already on PATH (a Debian package or a build from source) is used as it is:
# analogue only runs `ngspice -b` as a subprocess.
command -v ngspice >/dev/null 2>&1 || pkgs+=(ngspice libngspice0)
if [ "${1:-}" = "--test" ]; then
  command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 \
    || pkgs+=(chromium)
fi
missing=()
for p in ${pkgs[@]+"${pkgs[@]}"}; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
echo "installing Debian packages: ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
