#!/usr/bin/env bash
# Writes a LAVA device dictionary for the aarch64 virtual board as a device
# of type gabarit-board (docs/hil-farm.md), and the board's hardware map:
#   virtual-board-device.sh AARCH64_BUILD STATE [GABARIT] > NAME.jinja2
# AARCH64_BUILD has gabarit-board, gabarit-hil-relay and the virtual board's
# cache (platform/linux/virtual-board/prepare.sh); STATE is a folder of the
# device's own, where the hardware map (STATE/board.yaml: the relay on a free
# TCP port), the power's process id and QEMU's log go. Power-on boots the
# board with the job's table (serve.sh --bundle), as a lab would have
# provisioned a real one; its console is on another free port.
set -euo pipefail
build=${1:?usage: virtual-board-device.sh AARCH64_BUILD STATE [GABARIT]}
state=${2:?usage: virtual-board-device.sh AARCH64_BUILD STATE [GABARIT]}
gabarit=${3:-gabarit}
here=$(cd "$(dirname "$0")" && pwd)
vb=$(cd "$here/../../platform/linux/virtual-board" && pwd)
build=$(cd "$build" && pwd)
mkdir -p "$state"
state=$(cd "$state" && pwd)
free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
relay_port=$(free_port) console_port=$(free_port)
sed "s/^relay: .*/relay: tcp:127.0.0.1:$relay_port/" "$here/../boards/virtual-board-tcp.yaml" > "$state/board.yaml"
power="bash $here/virtual-board-power.sh"
serve="bash $vb/serve.sh --cache $build/virtual-board/cache --board $build/platform/linux/gabarit-board"
serve+=" --relay $build/platform/linux/gabarit-hil-relay --port $relay_port --console-port $console_port --log $state/qemu.log"
cat <<DICT
{% extends 'gabarit-board.jinja2' %}
{% set gabarit = '$gabarit' %}
{% set gabarit_board = '$state/board.yaml' %}
{% set connection_command = 'bash $here/virtual-board-console.sh $console_port' %}
{% set power_on_command = '$power on $state -- $serve --bundle ' ~ gabarit_bundle %}
{% set hard_reset_command = power_on_command %}
{% set power_off_command = '$power off $state' %}
DICT
