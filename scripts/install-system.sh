#!/usr/bin/env bash
# Install the Debian packages analogue needs, only those missing (idempotent; needs root or sudo).
#   scripts/install-system.sh            ngspice + libngspice0 (simulation)
#   scripts/install-system.sh --test     also chromium (the report page is loaded headless in tests)
set -euo pipefail
pkgs=(ngspice libngspice0)
[ "${1:-}" = "--test" ] && pkgs+=(chromium)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
echo "installing Debian packages: ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
