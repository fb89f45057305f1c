#!/usr/bin/env bash
# Network namespaces that stand in for several hosts on one machine: K "hosts" joined by
# veth pairs to a bridge that lives in its own namespace, so nothing outside the
# namespaces made here is touched (no host interfaces, no host addresses, no host routes).
#
#   scripts/netns/netns.sh up PREFIX K [SUBNET] [--block-multicast]
#       creates namespaces PREFIX-br (bridge) and PREFIX-0 .. PREFIX-(K-1); host k gets
#       SUBNET.(k+1)/24 (SUBNET defaults to 10.77.0) on its interface eth0, loopback up,
#       and a multicast route. --block-multicast drops multicast in every host with nftables
#       (to exercise unicast discovery: --peers or the discovery server).
#   scripts/netns/netns.sh exec PREFIX k COMMAND...   runs COMMAND inside host k
#   scripts/netns/netns.sh addr PREFIX k [SUBNET]     prints host k's address
#   scripts/netns/netns.sh down PREFIX                removes every namespace named PREFIX-*
#   scripts/netns/netns.sh check                      exit 0 if namespaces can be created here
#   scripts/netns/netns.sh loss PREFIX k PERCENT      drops PERCENT% of the Ethernet frames on
#       host k's link, both ways (nftables `numgen random` on the netdev ingress hook of both
#       ends of its veth pair: every frame, IP fragments included, is a separate draw).
#       PERCENT 0 removes the rule. Only inside the namespaces made by `up`.
#
# Needs root (CAP_NET_ADMIN) and iproute2. `up` removes leftovers of the same PREFIX first.
set -euo pipefail

die() { echo "netns.sh: $*" >&2; exit 2; }

list_ns() { ip netns list 2>/dev/null | awk '{print $1}' | grep -E "^$1-" || true; }

down() {
  local prefix=$1
  for ns in $(list_ns "$prefix"); do ip netns del "$ns" 2>/dev/null || true; done
}

check() {
  local probe="tessera-probe-$$"
  if ip netns add "$probe" 2>/dev/null; then
    ip netns del "$probe"
    return 0
  fi
  echo "netns.sh: cannot create network namespaces here (need root / CAP_NET_ADMIN)" >&2
  return 1
}

up() {
  local prefix=$1 k=$2 subnet=${3:-10.77.0} block=${4:-}
  [[ $k =~ ^[0-9]+$ && $k -ge 1 && $k -le 50 ]] || die "K must be 1..50"
  [[ $subnet =~ ^10\.77\.[0-9]{1,3}$ ]] || die "SUBNET must look like 10.77.X (addresses stay in 10.77.0.0/16)"
  down "$prefix"
  local br="$prefix-br"
  ip netns add "$br"
  ip -n "$br" link add br0 type bridge
  ip -n "$br" link set br0 up
  ip -n "$br" link set lo up
  for ((h = 0; h < k; h++)); do
    local ns="$prefix-$h"
    ip netns add "$ns"
    # Create the pair inside the bridge namespace, then move one end into the host.
    ip -n "$br" link add "p$h" type veth peer name eth0 netns "$ns"
    ip -n "$br" link set "p$h" master br0
    ip -n "$br" link set "p$h" up
    ip -n "$ns" link set lo up
    ip -n "$ns" link set eth0 up
    ip -n "$ns" addr add "$subnet.$((h + 1))/24" dev eth0
    ip -n "$ns" route add 224.0.0.0/4 dev eth0
    if [[ $block == --block-multicast ]]; then
      ip netns exec "$ns" nft -f - <<NFT
table inet tessera_block_mc {
  chain out { type filter hook output priority 0; ip daddr 224.0.0.0/4 drop; }
  chain in { type filter hook input priority 0; ip daddr 224.0.0.0/4 drop; }
}
NFT
    fi
  done
}

loss() {
  local prefix=$1 h=$2 pct=$3
  [[ $pct =~ ^[0-9]+$ && $pct -le 100 ]] || die "PERCENT must be 0..100"
  ip netns list | awk '{print $1}' | grep -qx "$prefix-$h" || die "no host $prefix-$h (run up first)"
  local ns dev
  for end in "$prefix-$h eth0" "$prefix-br p$h"; do
    read -r ns dev <<<"$end"
    ip netns exec "$ns" nft delete table netdev tessera_loss 2>/dev/null || true
    [[ $pct -eq 0 ]] && continue
    ip netns exec "$ns" nft -f - <<NFT
table netdev tessera_loss {
  chain in { type filter hook ingress device $dev priority 0; numgen random mod 100 < $pct counter drop; }
}
NFT
  done
}

cmd=${1:-}
case $cmd in
  up) [[ $# -ge 3 ]] || die "usage: up PREFIX K [SUBNET] [--block-multicast]"; up "$2" "$3" "${4:-10.77.0}" "${5:-}" ;;
  down) [[ $# -eq 2 ]] || die "usage: down PREFIX"; down "$2" ;;
  exec) [[ $# -ge 4 ]] || die "usage: exec PREFIX k COMMAND..."; ns="$2-$3"; shift 3; exec ip netns exec "$ns" "$@" ;;
  addr) [[ $# -ge 3 ]] || die "usage: addr PREFIX k [SUBNET]"; echo "${4:-10.77.0}.$(($3 + 1))" ;;
  check) check ;;
  loss) [[ $# -eq 4 ]] || die "usage: loss PREFIX k PERCENT"; loss "$2" "$3" "$4" ;;
  *) die "usage: netns.sh up|down|exec|addr|check|loss ... (see the header of this script)" ;;
esac
