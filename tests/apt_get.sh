# apt_get ARGS...: apt-get, waiting (5 min at most) while another apt-get or dpkg holds its
# locks. Sourced by tests/slurm/slurm.sh and tests/wine/toolchain.sh. A script that defines
# `apt_installed` (success once what it installs is there) stops waiting as soon as someone
# else's install has put it there.
apt_get() {
  local i out
  for i in $(seq 1 60); do
    if out=$(apt-get -o DPkg::Lock::Timeout=300 "$@" 2>&1); then
      return 0
    fi
    if ! grep -qiE 'could not get lock|unable to lock' <<<"$out"; then
      echo "$out" | tail -20 >&2
      return 1
    fi
    if declare -F apt_installed >/dev/null && apt_installed; then
      return 0  # someone else's install just finished
    fi
    sleep 5
  done
  echo "$out" | tail -20 >&2
  return 1
}
