#!/usr/bin/env bash
# Installs swmpm's build and run dependencies from Debian 12 packages (run as root; idempotent).
set -euo pipefail
packages=(build-essential cmake git libeigen3-dev libvtk9-dev libgmsh-dev libcgal-dev
  libsuitesparse-dev libopenblas0-serial openmpi-bin libopenmpi-dev petsc-dev libhypre-dev pkg-config nlohmann-json3-dev libcli11-dev libgtest-dev libmuparser-dev gnuplot-nox
  chromium)  # chromium: the test that renders report.html headless, as a reader's browser would
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if ((${#missing[@]})); then
  apt-get update -q
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
