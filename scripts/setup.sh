#!/usr/bin/env bash
# Installs robotkit into ./.venv (Debian 12 / Python >= 3.11). With --check, also the validators
# `robotkit check` runs (check_urdf, `ign sdf`; the GitHub action uses this). With --test, also what the
# tests need: pytest, MuJoCo and Playwright from PyPI, Chromium, and the validators check_urdf
# (liburdfdom-tools) and `ign sdf` (libsdformat-dev, ignition-tools) from Debian's packages, and
# Debian's ROS 1 (catkin, roslaunch, RViz, tf2, Xvfb) that the generated ROS packages are launched with.
set -euo pipefail
cd "$(dirname "$0")/.."

# What the quick start's build needs (main_need: setup.sh fails without it) and what `robotkit check`
# and the tests need (apt_need: a warning, but a failure under CI, where those tests would fail).
main_need=()
command -v python3 >/dev/null || main_need+=(python3)  # a bare container (debian:12)
python3 -c "import ensurepip, venv" 2>/dev/null || main_need+=(python3-venv)
# OSMesa: MuJoCo renders the picture report offscreen, with no display
{ ldconfig -p || /sbin/ldconfig -p; } 2>/dev/null | grep -q libOSMesa.so || main_need+=(libosmesa6)  # /sbin: not on a user's PATH
apt_need=()
if [ "${1:-}" = "--test" ] || [ "${1:-}" = "--check" ]; then
  command -v check_urdf >/dev/null || apt_need+=(liburdfdom-tools)
  command -v ign >/dev/null || apt_need+=(libsdformat-dev ignition-tools)
fi
if [ "${1:-}" = "--test" ]; then
  command -v chromium >/dev/null || apt_need+=(chromium)  # the report and viewer tests (Playwright)
  # ROS 1 from Debian 12, for the generated catkin packages: build, launch, RViz under Xvfb, tf2
  ros1=(ros-core rosbash rospack-tools catkin python3-catkin-pkg python3-empy cmake g++ make
        ros-robot-state-publisher joint-state-publisher joint-state-publisher-gui rviz python3-rospy
        python3-tf2-ros tf2-tools xvfb)
  { command -v catkin_make && command -v roslaunch && command -v rviz && command -v Xvfb \
    && /usr/bin/python3 -c "import rospy, tf2_ros"; } >/dev/null 2>&1 || apt_need+=("${ros1[@]}")
fi
sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"
apt_install() {  # apt_install PACKAGE...: install them; else print why (apt's first "E:" line) and return 1
  local log
  log=$(DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" 2>&1 >/dev/null) && return 0
  why=$(grep -m1 '^E: ' <<<"$log" || tail -n1 <<<"$log")
  why=${why#E: }
  return 1
}
if [ $((${#main_need[@]} + ${#apt_need[@]})) -gt 0 ]; then
  all_need=("${main_need[@]}" "${apt_need[@]}")
  echo "installing Debian packages: ${all_need[*]}" >&2
  $sudo apt-get update -qq >/dev/null 2>&1 || true
fi
if [ ${#main_need[@]} -gt 0 ] && ! apt_install "${main_need[@]}"; then
  echo "setup.sh: could not install ${main_need[*]} (${why:-apt-get failed}); run: ${sudo:+$sudo }apt-get install -y ${main_need[*]}" >&2
  exit 1
fi
if [ ${#apt_need[@]} -gt 0 ] && ! apt_install "${apt_need[@]}"; then
  line="could not install ${apt_need[*]} (${why:-apt-get failed}); run: ${sudo:+$sudo }apt-get install -y ${apt_need[*]}"
  if [ -n "${CI:-}" ]; then echo "setup.sh: $line" >&2; exit 1; fi  # the tests that need them would fail
  echo "setup.sh: warning: $line (the checks and tests that need them will not run)" >&2
fi

[ -x .venv/bin/python ] || python3 -m venv .venv
extra=""; [ "${1:-}" = "--test" ] && extra="[test]"
if ! log=$(.venv/bin/python -m pip install -q --disable-pip-version-check -e ".${extra}" 2>&1); then
  [ -z "$log" ] || grep -v "^WARNING: Location" <<<"$log" >&2 || true
  echo "setup.sh: pip could not install robotkit (its error above); run: .venv/bin/python -m pip install -e '.${extra}'" >&2
  exit 1
fi
[ -z "$log" ] || grep -v "^WARNING: Location" <<<"$log" || true
.venv/bin/python -c "import robotkit" # fail loudly if the install did not work
