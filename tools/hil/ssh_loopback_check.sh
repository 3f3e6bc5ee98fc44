#!/usr/bin/env bash
# The HIL runner's SSH transport without a board: Debian's sshd on 127.0.0.1 (its own host key,
# config and authorised key in a temporary folder), the runner connecting to it as to a board
# and running the board's aarch64 binaries there under qemu-aarch64 (this machine is x86-64).
# A subset of the suite keeps it short; the whole suite runs through the qemu: transport.
#   tools/hil/ssh_loopback_check.sh <board>
set -euo pipefail
cd "$(dirname "$0")/../.."
board=${1:?usage: tools/hil/ssh_loopback_check.sh <board>}
dir=$(mktemp -d)
pid=""
cleanup() {
  if [ -n "$pid" ]; then kill "$pid" 2>/dev/null || true; fi
  rm -rf "$dir"
}
trap cleanup EXIT
ssh-keygen -q -t ed25519 -N '' -f "$dir/host_key"
ssh-keygen -q -t ed25519 -N '' -f "$dir/client_key"
cp "$dir/client_key.pub" "$dir/authorized_keys"
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
cat >"$dir/sshd_config" <<CONF
ListenAddress 127.0.0.1
Port $port
HostKey $dir/host_key
AuthorizedKeysFile $dir/authorized_keys
PasswordAuthentication no
KbdInteractiveAuthentication no
PermitRootLogin prohibit-password
StrictModes no
UsePAM no
PidFile $dir/sshd.pid
CONF
cat >"$dir/ssh_config" <<CONF
Host 127.0.0.1
  IdentityFile $dir/client_key
  IdentitiesOnly yes
  UserKnownHostsFile $dir/known_hosts
  StrictHostKeyChecking accept-new
  LogLevel ERROR
CONF
# sshd wants its privilege-separation folder when it runs as root.
if [ "$(id -u)" -eq 0 ]; then mkdir -p /run/sshd; fi
/usr/sbin/sshd -f "$dir/sshd_config" -D -e 2>"$dir/sshd.log" &
pid=$!
for _ in $(seq 50); do
  ssh -F "$dir/ssh_config" -p "$port" -o BatchMode=yes "$(id -un)@127.0.0.1" true 2>/dev/null && break
  sleep 0.1
done
echo "=== HIL runner over SSH to sshd on 127.0.0.1:$port ($(date +%T))"
tools/hil/run.py "$board" "$(id -un)@127.0.0.1:$port" --ssh-config "$dir/ssh_config" \
  --remote-prefix qemu-aarch64 --binary test_runtime --binary test_link --binary test_hardware \
  --only '^(Board|Hardware|Mavlink)\.' || {
  echo "sshd's log:" >&2
  cat "$dir/sshd.log" >&2
  exit 1
}
