#!/usr/bin/env bash
# Who may talk to the flight software (docs/can.md, "Who can talk to the bus"): the UDP CAN
# transport is local to the host by default. Two network namespaces on a veth pair stand for two
# hosts on one LAN: host B plays a candump log onto udp:PORT with LAN scope; on host A, `sdins fsw`
#  - with the default (local) scope receives none of it and counts every datagram as foreign;
#  - with ?scope=lan receives the frames;
# and a player on B with the default scope reaches nobody on A (hop limit 0: nothing leaves B).
# Exit 77 (skipped) without root / network namespaces.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
if [ "$(id -u)" != 0 ] || ! command -v ip > /dev/null || ! ip netns add "sdins_probe_$$" 2> /dev/null; then
  echo "skipped: needs root and ip netns (network namespaces)"
  exit 77
fi
ip netns del "sdins_probe_$$"
na="sdins_fa_$$" nb="sdins_fb_$$" va="sfa$$" vb="sfb$$"
cleanup() {
  ip netns del "$na" 2> /dev/null
  ip netns del "$nb" 2> /dev/null
}
trap cleanup EXIT
ip netns add "$na" && ip netns add "$nb" || fail "cannot create namespaces"
ip link add "$va" type veth peer name "$vb" || fail "cannot create a veth pair"
ip link set "$va" netns "$na" && ip link set "$vb" netns "$nb" || fail "cannot move the veth ends"
host() {  # host NS IFACE N: loopback and the veth up, addresses fd5d::N and 10.213.0.N, default routes
  ip netns exec "$1" sysctl -qw "net.ipv6.conf.$2.accept_dad=0"  # no tentative addresses
  ip -n "$1" link set lo up
  ip -n "$1" link set "$2" up
  ip -n "$1" addr add "fd5d::$3/64" dev "$2" nodad
  ip -n "$1" addr add "10.213.0.$3/24" dev "$2"
  ip -n "$1" -6 route add default dev "$2"
  ip -n "$1" route add default dev "$2"
}
host "$na" "$va" 1
host "$nb" "$vb" 2

"$sdins" can encode --duration 2 --out "$out/frames.log" > /dev/null 2>&1 || fail "can encode failed"
frames=$(grep -c '^(' "$out/frames.log")
port=$((34000 + $$ % 2000))

# fsw_on_a NAME BUS: fsw in namespace A on BUS, waits until it listens; sets $fsw_pid.
fsw_on_a() {
  ip netns exec "$na" "$sdins" fsw --can "$2" --idle-timeout 3 --lcm-url none --json "$out/$1.json" \
    > "$out/$1.log" 2> "$out/$1.err" &
  fsw_pid=$!
  for _ in $(seq 100); do
    grep -q listening "$out/$1.err" 2> /dev/null && return 0
    sleep 0.1
  done
  cat "$out/$1.err" >&2
  fail "$1: fsw did not start listening"
}
# play_on_b NAME BUS: plays the log from namespace B.
play_on_b() {
  timeout 20 ip netns exec "$nb" "$sdins" can play "$out/frames.log" --can "$2" --gap 0.0005 > "$out/$1_play.log" 2>&1 ||
    { cat "$out/$1_play.log" >&2; fail "$1: can play on B failed"; }
}
bus_count() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['bus'][sys.argv[2]])" "$out/$1.json" "$2"; }

# 1. Default scope on A: nothing reaches the flight software, every datagram from B is counted.
fsw_on_a local "udp:$port"
play_on_b local "udp:$port?scope=lan"
wait "$fsw_pid"
rc=$?
[ "$rc" = 2 ] || { cat "$out/local.log" >&2; fail "local: fsw exit $rc, expected 2 (silent bus)"; }
[ "$(bus_count local received)" = 0 ] || fail "local: fsw received frames from another host"
[ "$(bus_count local foreign_dropped)" = "$frames" ] ||
  fail "local: $(bus_count local foreign_dropped) datagrams counted as foreign, $frames sent"
says local "datagrams from other hosts dropped"
cases=$((cases + 1))

# 2. LAN scope on A: the frames from B reach the flight software.
fsw_on_a lan "udp:$port?scope=lan"
play_on_b lan "udp:$port?scope=lan"
wait "$fsw_pid"
[ "$(bus_count lan received)" = "$frames" ] || fail "lan: fsw received $(bus_count lan received) of $frames frames"
[ "$(bus_count lan foreign_dropped)" = 0 ] || fail "lan: datagrams dropped as foreign"
cases=$((cases + 1))

# 3. A default-scope player on B reaches nobody on A (hop limit 0), not even a LAN-scope listener.
fsw_on_a quiet "udp:$port?scope=lan"
play_on_b quiet "udp:$port"
wait "$fsw_pid"
[ "$(bus_count quiet received)" = 0 ] || fail "quiet: a local-scope player's frames left its host"
cases=$((cases + 1))

# 4. The same with an IPv4 group (joined and sent on lo by default).
fsw_on_a v4 "udp:239.74.163.2:$port"
play_on_b v4 "udp:239.74.163.2:$port?scope=lan"
wait "$fsw_pid"
[ "$(bus_count v4 received)" = 0 ] || fail "v4: fsw received frames from another host"
fsw_on_a v4lan "udp:239.74.163.2:$port?scope=lan"
play_on_b v4lan "udp:239.74.163.2:$port?scope=lan"
wait "$fsw_pid"
[ "$(bus_count v4lan received)" = "$frames" ] || fail "v4lan: fsw received $(bus_count v4lan received) of $frames"
cases=$((cases + 2))

# 5. Bad scope arguments are refused naming the key.
run nonzero scope_bad -- "$sdins" can dump --can "udp:$port?scope=world" --timeout 1
says scope_bad "scope 'world'"
run nonzero scope_key -- "$sdins" can dump --can "udp:$port?ttl=3" --timeout 1
says scope_key "unknown key 'ttl'"
run nonzero scope_iface -- "$sdins" can dump --can "udp:$port?iface=lo" --timeout 1
says scope_iface "is for scope=lan"
run nonzero scope_noiface -- "$sdins" can dump --can "udp:$port?scope=lan&iface=nosuch0" --timeout 1
says scope_noiface "no such interface"
done_ok
