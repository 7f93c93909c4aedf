# shellcheck shell=bash
# Sourced by run-vm.sh and run-booted.sh: the virtual board's user network
# with the host ports forwarded to the guest's.
#
# forwarded_network NAME OUT SPEC...: sets the array net_args to QEMU's
# arguments for a virtio network card on QEMU's user network (restrict=on:
# the guest reaches nothing outside) forwarding each SPEC, [HOSTPORT:]GUESTPORT;
# a missing host port is picked just before QEMU starts among those no socket
# of this machine uses. Writes one line "GUESTPORT HOSTPORT" per SPEC to
# OUT/forwards and says it on stderr as NAME. No SPEC: net_args is empty.
forwarded_network() {
  local name=$1 out=$2 netdev f guest_port host_port
  shift 2
  net_args=()
  [ $# -gt 0 ] || return 0
  netdev="user,id=net0,restrict=on"
  : > "$out/forwards"
  for f in "$@"; do
    guest_port=${f#*:} host_port=""
    [ "$f" = "$guest_port" ] || host_port=${f%%:*}
    if [ -z "$host_port" ]; then
      for _ in $(seq 1 100); do
        host_port=$((20000 + RANDOM % 40000))
        forwarded_port_in_use "$host_port" || break
      done
    fi
    netdev+=",hostfwd=tcp:127.0.0.1:$host_port-:$guest_port"
    echo "$guest_port $host_port" >> "$out/forwards"
    echo "$name: the guest's port $guest_port is 127.0.0.1:$host_port here" >&2
  done
  # romfile= : no option ROM (its iPXE file is in ipxe-qemu; the kernel needs none).
  # shellcheck disable=SC2034 # the caller's
  net_args=(-netdev "$netdev" -device "virtio-net-pci,netdev=net0,romfile=")
}

# Whether a TCP socket of this machine uses PORT (listening or connected).
forwarded_port_in_use() {
  local hex
  hex=$(printf ':%04X' "$1")
  awk -v p="$hex" 'FNR > 1 && substr($2, length($2) - 4) == p { found = 1 } END { exit !found }' \
    /proc/net/tcp /proc/net/tcp6 2> /dev/null
}
