#!/usr/bin/env bash
# Runs the LcmNetns.* unit tests inside a fresh network namespace (`unshare -n`: loopback only, no
# routes), the situation the multicast route in docs/lcm.md is for.
#   no-route:        as created: LCM udpm cannot be created -> log-only fallback.
#   loopback-route:  lo up + `ip route add 224.0.0.0/4 dev lo` -> udpm works on loopback.
# Exit 77 (skipped) when namespaces cannot be created here (needs root / CAP_SYS_ADMIN).
set -u
bin=${1:?usage: lcm_netns.sh UNIT_TEST_BINARY MODE}
mode=${2:?usage: lcm_netns.sh UNIT_TEST_BINARY MODE}
if ! unshare -n true 2>/dev/null; then
  echo "skipped: cannot create a network namespace here (unshare -n needs CAP_SYS_ADMIN)"
  exit 77
fi
if ! command -v ip >/dev/null; then
  echo "skipped: no ip command (iproute2)"
  exit 77
fi
case "$mode" in
  no-route)
    exec unshare -n env SDINS_LCM_NETNS=no-route "$bin" --gtest_filter='LcmNetns.NoMulticastRoute*' ;;
  loopback-route)
    exec unshare -n sh -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec env SDINS_LCM_NETNS=loopback-route "$0" --gtest_filter="LcmNetns.LoopbackRoute*"' "$bin" ;;
  *) echo "unknown mode $mode"; exit 2 ;;
esac
