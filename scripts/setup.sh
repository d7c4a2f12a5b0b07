#!/usr/bin/env bash
# Installs what ircache needs on a fresh Debian machine: Embree 3 (the ray-tracing core), a C
# toolchain, Chromium (the walkthrough's end-to-end test drives it headless), and the Vulkan
# loader with Mesa's lavapipe (a software Vulkan device: the GPU passes' tests run on it where
# the machine has no GPU). Rust itself comes from rustup. Safe to run again: it installs only what is missing.
set -euo pipefail
need=()
dpkg -s libembree-dev >/dev/null 2>&1 || need+=(libembree-dev)
command -v cc >/dev/null 2>&1 || need+=(build-essential)
command -v pkg-config >/dev/null 2>&1 || need+=(pkg-config)
command -v chromium >/dev/null 2>&1 || need+=(chromium)
dpkg -s libvulkan1 >/dev/null 2>&1 || need+=(libvulkan1)
dpkg -s mesa-vulkan-drivers >/dev/null 2>&1 || need+=(mesa-vulkan-drivers)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}"
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install Rust with rustup (https://rustup.rs) and run again" >&2
  exit 1
fi
