#!/usr/bin/env bash
# The aarch64 virtual board's console, for a LAVA device's connection_command
# (docs/hil-farm.md): the board serves its console on a TCP port of
# 127.0.0.1 only while it is powered (serve.sh --console-port), and LAVA
# connects before it powers the board on, so this waits for it (up to ten
# minutes), then joins it to stdin and stdout until the board powers off.
#   virtual-board-console.sh PORT
set -uo pipefail
port=${1:?usage: virtual-board-console.sh PORT}
for _ in $(seq 3000); do
  { exec 3<> "/dev/tcp/127.0.0.1/$port"; } 2> /dev/null && break
  sleep 0.2
done
{ : >&3; } 2> /dev/null || { echo "virtual-board-console.sh: no console on 127.0.0.1:$port" >&2; exit 1; }
cat >&3 &
cat <&3
kill $! 2> /dev/null
