#!/bin/sh
# px4-entrypoint.sh [PX4 ARGS...] : the entrypoint of a uavtest PX4 SITL image (/usr/local/bin/px4-sitl).
#
# Runs the packaged PX4 SITL build (/opt/px4: bin/, etc/, parameters.json) as instance 0 in daemon
# mode, with its working directory (parameters, dataman, log/) in PX4_WORKDIR, default the current
# directory: the uavtest operator sets the container's workingDir to the pod's shared emptyDir, so
# the runner finds PX4's log/<date>/<time>.ulg there. Instance 0 sends MAVLink to 127.0.0.1:14540.
#
# Environment, all optional:
#   PX4_SIM_MODEL          default sihsim_quadx (SIH: physics inside PX4, no external simulator)
#   PX4_HOME_LAT/LON/ALT   the home (degrees, metres). PX4 <= v1.15 takes SIH_LOC_LAT0/LON0 as INT
#                          degrees * 1e7: when the packaged parameters.json says so, a value written
#                          in degrees (with a '.') is converted; v1.16+ takes degrees as they are
#   PX4_SIM_SPEED_FACTOR   times real time (rcS computes with `bc`)
#   PX4_WORKDIR            PX4's working directory (must be writable)
set -eu
PX4_ROOT=${PX4_ROOT:-/opt/px4}
WORKDIR=${PX4_WORKDIR:-$PWD}
export PX4_SIM_MODEL="${PX4_SIM_MODEL:-sihsim_quadx}"

# true when this build's SIH_LOC_LAT0 is an Int32 (degrees * 1e7): its parameters.json entry
sih_latlon_is_int() {
  [ -f "$PX4_ROOT/parameters.json" ] || return 1
  grep -o '{[^{}]*"name": *"SIH_LOC_LAT0"[^{}]*}' "$PX4_ROOT/parameters.json" | grep -q '"type": *"Int'
}

if sih_latlon_is_int; then
  for var in PX4_HOME_LAT PX4_HOME_LON; do
    eval "value=\${$var:-}"
    case $value in
      *.*) eval "export $var=$(awk -v x="$value" 'BEGIN { printf "%.0f", x * 1e7 }')" ;;
    esac
  done
fi

mkdir -p "$WORKDIR"
cd "$WORKDIR"
echo "px4-sitl: model $PX4_SIM_MODEL, home ${PX4_HOME_LAT:-default} ${PX4_HOME_LON:-default}" \
  "${PX4_HOME_ALT:-default}, speed factor ${PX4_SIM_SPEED_FACTOR:-1}, working directory $WORKDIR" >&2
# PX4 in the background and the shell waiting: a SIGTERM (the pod ending) reaches PX4 even when this
# shell is PID 1, which ignores signals it has no handler for
"$PX4_ROOT/bin/px4" -i 0 -w "$WORKDIR" -d "$PX4_ROOT/etc" "$@" &
pid=$!
trap 'kill -TERM "$pid" 2>/dev/null' TERM INT
while :; do
  status=0
  wait "$pid" || status=$?
  kill -0 "$pid" 2>/dev/null || exit "$status"   # wait was interrupted by the trap: wait again
done
