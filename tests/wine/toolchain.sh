#!/usr/bin/env bash
# The Windows toolchain of the FMUs: rustup's x86_64-pc-windows-gnu target and Debian's
# mingw-w64 build the win64 DLL; Debian's wine64 runs it in the tests.
#
#   tests/wine/toolchain.sh check-build   exit 0 if the win64 DLL can be built here, else 1
#                                         with the reason on stderr
#   tests/wine/toolchain.sh check-wine    print the Wine program that runs 64-bit Windows
#                                         programs, else exit 1 with the reason on stderr
#   tests/wine/toolchain.sh install       install what is missing: the Rust target with
#                                         rustup, gcc-mingw-w64-x86-64 and wine64 with
#                                         apt-get (as root)
#
# Exit status of `install`: 0 everything is there; 77 it cannot be had here (not root, no
# apt-get or rustup, a download failed), with the reason on stderr: `make test` then skips
# the Windows checks, or fails under CI; 1 anything else.
set -euo pipefail

TARGET=x86_64-pc-windows-gnu
MINGW_GCC=x86_64-w64-mingw32-gcc
APT_PACKAGES=(gcc-mingw-w64-x86-64 wine64)

unavailable() { echo "toolchain.sh: $*" >&2; exit 77; }

have_target() {
  local sysroot
  sysroot=$(rustc --print sysroot 2>/dev/null) || return 1
  [ -d "$sysroot/lib/rustlib/$TARGET/lib" ]
}

wine_program() {
  local w
  for w in "$(command -v wine64 || true)" /usr/lib/wine/wine64 /usr/lib64/wine/wine64 \
           "$(command -v wine || true)"; do
    if [ -n "$w" ] && [ -x "$w" ]; then
      echo "$w"
      return 0
    fi
  done
  return 1
}

check_build() {
  command -v rustc >/dev/null 2>&1 || { echo "rustc is not on PATH" >&2; return 1; }
  have_target || { echo "the Rust target $TARGET is not installed (rustup target add $TARGET)" >&2; return 1; }
  command -v "$MINGW_GCC" >/dev/null 2>&1 \
    || { echo "$MINGW_GCC is missing (Debian: apt-get install gcc-mingw-w64-x86-64)" >&2; return 1; }
}

check_wine() {
  wine_program || { echo "no wine64 (Debian: apt-get install wine64)" >&2; return 1; }
}

# apt_get (the waiting apt-get) and its hook apt_installed.
. "$(dirname "${BASH_SOURCE[0]}")/../apt_get.sh"

install() {
  if ! have_target; then
    command -v rustup >/dev/null 2>&1 \
      || unavailable "the Rust target $TARGET is missing and there is no rustup to add it"
    echo "toolchain.sh: rustup target add $TARGET" >&2
    rustup target add "$TARGET" >&2 || unavailable "rustup target add $TARGET failed"
  fi
  if command -v "$MINGW_GCC" >/dev/null 2>&1 && wine_program >/dev/null; then
    return 0
  fi
  [ "$(id -u)" = 0 ] || unavailable "${APT_PACKAGES[*]} are not installed and we are not root to apt-get them"
  command -v apt-get >/dev/null 2>&1 || unavailable "${APT_PACKAGES[*]} are not installed and there is no apt-get"
  echo "toolchain.sh: installing ${APT_PACKAGES[*]} (apt-get)" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt_get update -q || unavailable "apt-get update failed"
  apt_get install -y -q --no-install-recommends "${APT_PACKAGES[@]}" \
    || unavailable "apt-get install ${APT_PACKAGES[*]} failed"
  check_build >&2 || unavailable "installed, but the win64 build is still not possible"
  check_wine >/dev/null || unavailable "installed, but wine64 is still missing"
}

case "${1:-}" in
  check-build) check_build ;;
  check-wine) check_wine ;;
  install) install ;;
  *) echo "usage: $0 check-build | check-wine | install" >&2; exit 2 ;;
esac
