#!/bin/sh
# shellcheck shell=dash
# The guest half of tests/vm/run_vm_booted.sh: run as root by the Debian
# disk's fpp-vm-hook.service (toolchain/vm/make-rootfs.sh) on the booted
# virtual ARM board, from the host's read-only /fpp/in, which holds the two
# packages (fpp-scanner_*_arm64.deb and the same repacked with a newer
# version, in new/) and board.yaml (the virtual board's devices, rpi5.yaml's
# http and settings). It installs the package as a user would and writes
# what it sees as KEY=VALUE lines to /out/results; the host asserts them.
# Where the host must act (curl through the forwarded port), it writes
# /out/NAME.ready and waits for the host's /out/NAME.done.
# Not `set -e`: every step records its result and the run goes on, so that
# one failure does not hide the others.
set -u
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
export DEBIAN_FRONTEND=noninteractive LC_ALL=C
results=/out/results
: > "$results"
res() {
  echo "$1=$2" >> "$results"
  echo "guest: $1=$2"
}
now() { cut -d' ' -f1 /proc/uptime; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
# wait_for SECONDS COMMAND...: until COMMAND succeeds; status 1 on timeout.
wait_for() {
  local limit=$(($1 * 10)) i=0
  shift
  while ! "$@" > /dev/null 2>&1; do
    i=$((i + 1))
    [ $i -lt $limit ] || return 1
    sleep 0.1
  done
}
wait_host() {
  : > "/out/$1.ready"
  echo "guest: waiting for the host ($1)"
  wait_for 300 test -e "/out/$1.done" || { res "host_$1" timeout; return 1; }
  res "host_$1" "done"
}
main_pid() { systemctl show -p MainPID --value fpp-scanner.service; }
listening_lines() { journalctl -u fpp-scanner.service -o cat --no-pager | grep -c 'http: listening on'; }
# More than $1 "listening" lines in the unit's journal.
listening_more_than() { [ "$(listening_lines)" -gt "$1" ]; }
# Active, with a main PID other than $1.
active_with_new_pid() {
  local p
  p=$(main_pid)
  [ "$p" != 0 ] && [ "$p" != "$1" ] && [ "$(systemctl is-active fpp-scanner.service)" = active ]
}

# --- The system as booted ---------------------------------------------------------
systemctl is-system-running --wait > /dev/null 2>&1
res system_state "$(systemctl is-system-running)"
systemctl --failed --no-legend --plain | awk '{ print $1 }' > /out/failed-units.txt
res failed_units "$(wc -l < /out/failed-units.txt)"
# "Startup finished in 1.9s (kernel) + 21.0s (userspace) = 22.9s"
res boot_finished "$(systemd-analyze time 2> /dev/null | sed -n 's/^Startup finished in .* = \([0-9.]*\)s.*$/\1/p;s/^Startup finished in .* = \([0-9]*\)min \([0-9.]*\)s.*$/\1 min \2/p' | head -n 1)"
res systemd_version "$(systemctl --version | sed -n '1s/^systemd \([0-9]*\).*/\1/p')"
# SocketBindAllow/Deny= are BPF programs that only a systemd built with
# libbpf (+BPF_FRAMEWORK) loads; without, it ignores them without a word.
res systemd_bpf_framework "$(systemctl --version | grep -o '[+-]BPF_FRAMEWORK')"
res guest_sh_started_s "$(now)"

# --- Install as a user would -------------------------------------------------------
deb=$(ls /fpp/in/fpp-scanner_*_arm64.deb)
newer=$(ls /fpp/in/new/fpp-scanner_*_arm64.deb)
cp "$deb" "$newer" /var/tmp/
deb=/var/tmp/$(basename "$deb")
newer=/var/tmp/$(basename "$newer")
t=$(now)
apt-get install -y "$deb" > /out/apt-install.log 2>&1
res install_status $?
res install_s "$(since "$t")"
res installed "$(dpkg-query -W -f '${db:Status-Status} ${Version}' fpp-scanner 2> /dev/null)"
res enabled_after_install "$(systemctl is-enabled fpp-scanner.service 2> /dev/null)"
res active_after_install "$(systemctl is-active fpp-scanner.service 2> /dev/null)"

# --- The postinst's token and user ---------------------------------------------------
token=/etc/fpp-scanner/token
res token_stat "$(stat -c '%a %U %G' "$token" 2> /dev/null)"
res token_format "$(grep -Ecx '[0-9a-f]{64}' "$token" 2> /dev/null) $(wc -l < "$token" 2> /dev/null)"
token_sum=$(sha256sum "$token" 2> /dev/null | cut -d' ' -f1)
res user "$(id -un fpp-scanner 2> /dev/null) $(id -Gn fpp-scanner 2> /dev/null | tr ' ' '\n' | sort | tr '\n' ' ')"
res user_shell "$(getent passwd fpp-scanner | cut -d: -f7)"
res gpiochip_group "$(stat -c '%G %a' /dev/gpiochip0 2> /dev/null)"
res drm_card "$(stat -c '%G %a' /dev/dri/card0 2> /dev/null)"

# --- The board, the camera, the service -------------------------------------------------
cp /fpp/in/board.yaml /etc/fpp-scanner/board.yaml
board_sum=$(sha256sum /etc/fpp-scanner/board.yaml | cut -d' ' -f1)
# Aravis's fake GigE camera on the loopback, as its own transient unit.
systemd-run --unit=fpp-fake-camera --quiet /usr/local/bin/arv-fake-gv-camera-0.8 -i 127.0.0.1
t=$(now)
systemctl enable --now fpp-scanner.service > /out/enable.log 2>&1
res enable_status $?
if wait_for 180 listening_more_than 0; then
  res listening_s "$(since "$t")"
else
  res listening_s never
fi
res active "$(systemctl is-active fpp-scanner.service)"
pid=$(main_pid)
res main_pid "$pid"
res process_user "$(stat -c %U "/proc/$pid" 2> /dev/null)"
# The running process's confinement, from the kernel.
res no_new_privs "$(sed -n 's/^NoNewPrivs:[[:space:]]*//p' "/proc/$pid/status")"
res seccomp "$(sed -n 's/^Seccomp:[[:space:]]*//p' "/proc/$pid/status")"
res cap_eff "$(sed -n 's/^CapEff:[[:space:]]*//p' "/proc/$pid/status")"
res cap_bnd "$(sed -n 's/^CapBnd:[[:space:]]*//p' "/proc/$pid/status")"
# ProtectSystem=strict: / read-only in the service's mount namespace, its
# state folder writable; ProtectHome: /root unreadable.
res ns_root_ro "$(nsenter -t "$pid" -m sh -c 'touch /usr/fpp-probe 2>&1 || true' | grep -c 'Read-only file system')"
res ns_etc_ro "$(nsenter -t "$pid" -m sh -c 'touch /etc/fpp-scanner/fpp-probe 2>&1 || true' | grep -c 'Read-only file system')"
res ns_home "$(nsenter -t "$pid" -m sh -c 'ls -A /root | wc -l')"
cp "$token" /out/token # for the host's curl
wait_host http

# --- systemd-analyze security on the running unit ----------------------------------------
systemd-analyze security --no-pager fpp-scanner.service > /out/security.txt 2>&1
res security_status $?
res exposure "$(sed -n 's/^.*Overall exposure level for fpp-scanner.service: \([0-9.]*\) \([A-Z]*\).*$/\1 \2/p' /out/security.txt)"

# --- SocketBindDeny= on the running unit ----------------------------------------------------
# A process placed in the service's own cgroup (whose BPF programs enforce
# SocketBindAllow/Deny) tries binds (TCP, or UDP with a second argument):
# the errno, 0 when bound.
cgroup=/sys/fs/cgroup$(systemctl show -p ControlGroup --value fpp-scanner.service)
cat > /run/bind-probe.pl << 'EOF2'
use Socket;
my $udp = ($ARGV[1] // "") eq "udp";
socket(my $s, PF_INET, $udp ? SOCK_DGRAM : SOCK_STREAM, 0) or die "socket: $!";
print bind($s, pack_sockaddr_in($ARGV[0], INADDR_ANY)) ? "0\n" : ($! + 0) . "\n";
EOF2
bind_probe() { perl /run/bind-probe.pl "$@"; }
in_unit_bind() {
  # shellcheck disable=SC2016 # $$ is the inner shell's
  sh -c 'echo $$ > "$1/cgroup.procs" && shift && exec perl /run/bind-probe.pl "$@"' sh "$cgroup" "$@"
}
res bind_outside_8081 "$(bind_probe 8081)"
res bind_unit_8081 "$(in_unit_bind 8081)"
res bind_unit_9000 "$(in_unit_bind 9000)"
res bind_unit_8080 "$(in_unit_bind 8080)"
res bind_unit_0 "$(in_unit_bind 0)"
res bind_unit_udp_0 "$(in_unit_bind 0 udp)"
res bind_unit_udp_40000 "$(in_unit_bind 40000 udp)"
res socket_bind_props "$(systemctl show -p SocketBindAllow -p SocketBindDeny fpp-scanner.service | tr '\n' ' ')"

# --- Restart= after SIGKILL ----------------------------------------------------------------
pid=$(main_pid)
restarts=$(systemctl show -p NRestarts --value fpp-scanner.service)
lines=$(listening_lines)
t=$(now)
kill -KILL "$pid"
if wait_for 60 active_with_new_pid "$pid"; then
  res restarted_s "$(since "$t")"
else
  res restarted_s never
fi
new_pid=$(main_pid)
res restart_pids "$pid $new_pid"
res nrestarts "$restarts $(systemctl show -p NRestarts --value fpp-scanner.service)"
wait_for 120 listening_more_than "$lines"
res listening_after_restart "$(listening_lines)"

# --- The journal ---------------------------------------------------------------------------------
journalctl -u fpp-scanner.service --no-pager -o short-monotonic > /out/journal.txt 2>&1
res journal_lines "$(wc -l < /out/journal.txt)"
res journal_ident "$(journalctl -u fpp-scanner.service -o verbose --no-pager | grep -c '^ *SYSLOG_IDENTIFIER=fpp-scanner$')"
res journal_sigkill "$(grep -c 'status=9/KILL' /out/journal.txt)"
res journal_warning_priority "$(journalctl -u fpp-scanner.service -p warning -o cat --no-pager | grep -c 'no table at')"

# --- Upgrade to a newer version -----------------------------------------------------------------
scans_before=$(find /var/lib/fpp-scanner/scans -mindepth 1 -maxdepth 1 | wc -l)
scans_sum_before=$(find /var/lib/fpp-scanner/scans -type f -exec sha256sum {} + | sort | sha256sum | cut -d' ' -f1)
res scans_before "$scans_before"
pid=$(main_pid)
lines=$(listening_lines)
t=$(now)
apt-get install -y "$newer" > /out/apt-upgrade.log 2>&1
res upgrade_status $?
res upgrade_s "$(since "$t")"
res upgraded "$(dpkg-query -W -f '${db:Status-Status} ${Version}' fpp-scanner 2> /dev/null)"
res token_kept "$([ "$(sha256sum "$token" 2> /dev/null | cut -d' ' -f1)" = "$token_sum" ] && echo yes || echo no)"
res token_stat_after_upgrade "$(stat -c '%a %U %G' "$token" 2> /dev/null)"
res board_kept "$([ "$(sha256sum /etc/fpp-scanner/board.yaml | cut -d' ' -f1)" = "$board_sum" ] && echo yes || echo no)"
res scans_after "$(find /var/lib/fpp-scanner/scans -mindepth 1 -maxdepth 1 | wc -l)"
res scans_kept "$([ "$(find /var/lib/fpp-scanner/scans -type f -exec sha256sum {} + | sort | sha256sum | cut -d' ' -f1)" = "$scans_sum_before" ] && echo yes || echo no)"
# postinst's try-restart: the new binary runs, listening again.
wait_for 120 listening_more_than "$lines"
res upgrade_pids "$pid $(main_pid)"
res active_after_upgrade "$(systemctl is-active fpp-scanner.service)"
res enabled_after_upgrade "$(systemctl is-enabled fpp-scanner.service 2> /dev/null)"
wait_host upgraded

# --- Remove, then purge ----------------------------------------------------------------------------
apt-get remove -y fpp-scanner > /out/apt-remove.log 2>&1
res remove_status $?
res after_remove "$([ -e "$token" ] && echo token) $([ -e /etc/fpp-scanner/board.yaml ] && echo board) $([ -e /usr/bin/fpp-scanner ] && echo binary) $(systemctl is-active fpp-scanner.service 2> /dev/null)"
res after_remove_scans "$(find /var/lib/fpp-scanner/scans -mindepth 1 -maxdepth 1 2> /dev/null | wc -l)"
apt-get purge -y fpp-scanner > /out/apt-purge.log 2>&1
res purge_status $?
res purged "$(dpkg-query -W -f '${db:Status-Status}' fpp-scanner 2> /dev/null || echo not-installed)"
res after_purge_etc "$(if [ -e /etc/fpp-scanner ]; then find /etc/fpp-scanner | tr '\n' ' '; else echo gone; fi)"
res after_purge_unit "$([ -e /lib/systemd/system/fpp-scanner.service ] && echo present || echo gone) $(systemctl is-enabled fpp-scanner.service 2> /dev/null || true)"
res after_purge_wants "$([ -L /etc/systemd/system/multi-user.target.wants/fpp-scanner.service ] && echo link || echo none)"
res after_purge_user "$(getent passwd fpp-scanner > /dev/null && echo kept || echo gone)"
res after_purge_state "$([ -e /var/lib/fpp-scanner ] && echo present || echo gone)"
res "done" yes
