#!/usr/bin/env bash
# One machine standing in for a LAVA farm (docs/hil-farm.md): a local LAVA
# server (PostgreSQL, the web API under gunicorn, the scheduler) and two
# workers, each with two QEMU mps2-an500 boards of gabarit's device type,
# all started and stopped here, as root, without systemd. Five jobs from
# `gabarit hil lava-job` are submitted with lavacli: four of the same
# firmware, and a fifth whose firmware has a bug on one frame (FAULTY_ELF:
# frame 5's pose a pixel off). With an aarch64 build (AARCH64_BUILD, its
# gabarit-board and gabarit-hil-relay), worker2 also has the virtual board as
# a device of type gabarit-board, and a sixth job runs on it. Checked:
#   - the first four ran at once (each started before any ended), on four
#     boards of two workers, and every pose of theirs is bit-identical to the
#     host's (their harness reports, collected by farm_report.py --collect);
#   - the sixth (if any) ran on the virtual board, every pose identical;
#   - all complete; farm_report.py merges their JUnit from the server's
#     API into one report that names the fifth job's board, the failing frame
#     and the failed pose check, and nothing else failed;
#   - the first job's file, run again by lava-run alone, gives the same
#     verdicts as through the server.
# Usage: lava_farm_test.sh GABARIT FIRMWARE_ELF FAULTY_ELF SOURCE_DIR [AARCH64_BUILD]
# Exit 77 (skipped) without lava-server, lava-dispatcher, lavacli,
# PostgreSQL 15 or root. The `hil-lava-farm` target of a cortex-m7 build runs it.
set -euo pipefail
gabarit=$1 firmware=$2 faulty=$3 source=$4 aarch64=${5:-}
vb=$source/platform/linux/virtual-board
if [ -n "$aarch64" ] && [ -x "$aarch64/platform/linux/gabarit-board" ] && [ -x "$aarch64/platform/linux/gabarit-hil-relay" ]; then
  bash "$vb/prepare.sh" "$aarch64/virtual-board/cache" > /dev/null
else
  echo "(no aarch64 build at '${aarch64}': the virtual board is not in this farm)"
  aarch64=""
fi
templates=$source/hil/lava
for tool in lava-server lava-worker lava-run lavacli gunicorn3 pg_ctlcluster runuser; do
  command -v $tool > /dev/null || { echo "SKIP: no $tool (apt-get install lava-server lava-dispatcher lavacli postgresql)"; exit 77; }
done
[ "$(id -u)" = 0 ] || { echo "SKIP: starts PostgreSQL and LAVA's daemons: run as root"; exit 77; }
work=$(mktemp -d /tmp/gabarit-farm-XXXXXX)
db=gabarit_farm_$$
pids=() started_postgres=0
as_postgres() { (cd / && runuser -u postgres -- psql -qc "$1"); }
cleanup() {
  [ -z "$aarch64" ] || bash "$templates/virtual-board-power.sh" off "$work/vb1" || true
  for pid in "${pids[@]}"; do kill -- -"$pid" 2> /dev/null || kill "$pid" 2> /dev/null || true; done
  as_postgres "DROP DATABASE IF EXISTS $db" > /dev/null 2>&1 || true
  as_postgres "DROP ROLE IF EXISTS $db" > /dev/null 2>&1 || true
  [ "$started_postgres" = 0 ] || pg_ctlcluster 15 main stop || true
  [ -n "${KEEP:-}" ] || rm -rf "$work"
}
trap cleanup EXIT
chmod 755 "$work"  # LAVA's scheduler runs as the lavaserver user: it must reach its log
cd "$work"
free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
# Starts a daemon in its own session (killed with its group at the end).
daemon() { local log=$1; shift; setsid "$@" > "$log" 2>&1 & pids+=($!); }

echo "--- PostgreSQL and the server's database"
if [ -z "$(pg_lsclusters -h 2> /dev/null | awk '$1 == 15 && $2 == "main" && $4 == "online"')" ]; then pg_ctlcluster 15 main start; started_postgres=1; fi
as_postgres "CREATE ROLE $db LOGIN PASSWORD 'gabarit' CREATEDB"
as_postgres "CREATE DATABASE $db OWNER $db"
mkdir -p devices device-types health-checks
cp "$templates"/*.jinja2 device-types/
export DATABASE_URL=postgres://$db:gabarit@127.0.0.1:5432/$db SECRET_KEY=gabarit-farm-test ALLOWED_HOSTS=127.0.0.1
export LAVA_YAML_SETTINGS_EXTRA_CONTEXT_VARIABLES='[gabarit_bundle]'
export LAVA_YAML_SETTINGS_DEVICES_PATH=$work/devices LAVA_YAML_SETTINGS_HEALTH_CHECKS_PATH=$work/health-checks
export LAVA_YAML_SETTINGS_DEVICE_TYPES_PATHS="[$work/device-types, /usr/share/lava-server/device-types]"
lava-server manage migrate > migrate.log
lava-server manage users add --superuser --staff --passwd gabarit admin > /dev/null
token=$(lava-server manage tokens add --user admin | tail -1)
lava-server manage device-types add gabarit-qemu-mps2-an500
for w in worker1 worker2; do
  lava-server manage workers add $w > /dev/null
  for b in 1 2; do
    printf "{%% extends 'gabarit-qemu-mps2-an500.jinja2' %%}\n{%% set gabarit_link_port = %s %%}\n{%% set gabarit = '%s' %%}\n" \
      "$(free_port)" "$gabarit" > devices/$w-board$b.jinja2
    lava-server manage devices add --device-type gabarit-qemu-mps2-an500 --worker $w $w-board$b
  done
done
if [ -n "$aarch64" ]; then
  # The virtual board as a lab's board (docs/hil-farm.md): its power by a
  # script, its console on a TCP port, its relay as its hardware map says.
  bash "$templates/virtual-board-device.sh" "$aarch64" "$work/vb1" "$gabarit" > devices/worker2-vb1.jinja2
  lava-server manage device-types add gabarit-board
  lava-server manage devices add --device-type gabarit-board --worker worker2 worker2-vb1
fi

echo "--- the server, the scheduler and two workers"
port=$(free_port)
url=http://127.0.0.1:$port
daemon gunicorn.log gunicorn3 lava_server.wsgi --worker-class eventlet --workers 2 --bind 127.0.0.1:$port
install -m 644 -o lavaserver /dev/null scheduler.log
daemon scheduler.out lava-server manage lava-scheduler --level INFO --log-file "$work/scheduler.log"
for _ in $(seq 100); do curl -sf -o /dev/null "$url/api/v0.2/" && break; sleep 0.2; done
for w in worker1 worker2; do
  mkdir -p $w
  daemon $w.out lava-worker --name $w --url "$url/" --token "$(lava-server manage workers details $w | awk '/^token/ {print $3}')" \
    --worker-dir "$work/$w" --log-file "$work/$w.log" --level INFO
done

echo "--- five jobs${aarch64:+, and a sixth on the virtual board}"
"$gabarit" synth --shape curve --frames 16 --noise 0.02 --size 96x96 --seed 11 -o seq > /dev/null
"$gabarit" tables build --model seq/model.pgm --binary --x -4:4:9 --y -4:4:9 -o seq/table.gbt > /dev/null
for i in 1 2 3 4; do
  "$gabarit" hil lava-job --sequence seq --firmware "$firmware" --name seq-$i --minutes 5 --out job$i > /dev/null
done
"$gabarit" hil lava-job --sequence seq --firmware "$faulty" --name seq-faulty --minutes 5 --out job5 > /dev/null
jobs=(1 2 3 4 5)
if [ -n "$aarch64" ]; then
  "$gabarit" hil lava-job --sequence seq --device-type gabarit-board --name seq-vb --minutes 5 --out job6 > /dev/null
  jobs+=(6)
fi
lava="lavacli --uri http://admin:$token@127.0.0.1:$port/RPC2"
ids=()
start=$SECONDS
for i in "${jobs[@]}"; do ids+=("$($lava jobs submit job$i/job.yaml)"); done
for id in "${ids[@]}"; do
  until $lava jobs show "$id" | grep -q "^state *: Finished"; do
    [ $((SECONDS - start)) -lt 900 ] || { echo "FAIL: job $id did not finish in 900 s"; exit 1; }
    sleep 3
  done
done
echo "${#ids[@]} jobs done in $((SECONDS - start)) s"

echo "--- the farm's report"
status=0
python3 "$templates/farm_report.py" --url "$url" --token "$token" --out merged-junit.xml --collect reports "${ids[@]}" > farm-report.txt || true
cat farm-report.txt
python3 - "$url" "$token" farm-report.txt "${ids[@]}" <<'PY' || status=1
import json, pathlib, sys, urllib.request
url, token, report, ids = sys.argv[1], sys.argv[2], open(sys.argv[3]).read(), sys.argv[4:]
def get(path):
    r = urllib.request.Request(url + path, headers={"Authorization": f"Token {token}"})
    return json.loads(urllib.request.urlopen(r, timeout=60).read())
jobs = [get(f"/api/v0.2/jobs/{i}/") for i in ids]
problems = []
boards = {j["actual_device"] for j in jobs[:4]}
if len(boards) != 4 or {b.split("-")[0] for b in boards} != {"worker1", "worker2"}:
    problems.append(f"the jobs ran on {sorted(boards)}, want four boards of two workers")
if max(j["start_time"] for j in jobs[:4]) >= min(j["end_time"] for j in jobs[:4]):
    problems.append("the jobs did not run at once: " + ", ".join(f"{j['start_time']}..{j['end_time']}" for j in jobs[:4]))
if len(jobs) > 5 and jobs[5]["actual_device"] != "worker2-vb1":
    problems.append(f"the sixth job ran on {jobs[5]['actual_device']}, want worker2-vb1")
for i, j in list(zip(ids[:4], jobs[:4])) + list(zip(ids[5:], jobs[5:])):
    summary = pathlib.Path(f"reports/{j['actual_device']}-job{i}/summary.json")
    s = json.loads(summary.read_text()) if summary.exists() else {}
    if s.get("poses") != 16 or s.get("poses_matching_reference") != 16:
        problems.append(f"job {i}: {s.get('poses_matching_reference')} of {s.get('poses')} poses identical to the host's, want 16 of 16")
if any(j["health"] != "Complete" for j in jobs):
    problems.append("health: " + ", ".join(j["health"] for j in jobs))
failing_board = jobs[4]["actual_device"]
failed = [l.split() for l in report.splitlines() if l.strip().startswith("FAILED")]
named = {f[4] for f in failed if f[1] == failing_board and f[3] == f"{ids[4]}:"}
want = {"gabarit-hil-frames.frame_000005", "gabarit-hil-checks.poses_match_reference"}
if named != want:
    problems.append(f"the report names {sorted(named)} on {failing_board}, job {ids[4]}; want {sorted(want)}")
if any(f[1] != failing_board or f[3] != f"{ids[4]}:" for f in failed):
    problems.append("a case failed in another job")
for p in problems:
    print("FAIL:", p)
sys.exit(1 if problems else 0)
PY

echo "--- the first job again, by lava-run alone"
curl -sf -H "Authorization: Token $token" "$url/api/v0.2/jobs/${ids[0]}/junit/" > server-junit.xml
python3 "$templates/render_device.py" devices/worker1-board1.jinja2 --context gabarit_bundle="$work/job1" > alone.yaml
alone=0
timeout 600 lava-run --job-id "gabarit-farm-alone-$$" --output-dir "$work/alone" --device alone.yaml job1/job.yaml > alone.log 2>&1 || alone=$?
python3 - server-junit.xml alone.log "$alone" <<'PY' || status=1
import json, sys, xml.etree.ElementTree as ET
server = {(s.get("name"), c.get("name")): ("fail" if c.find("failure") is not None else "skip" if c.find("skipped") is not None else "pass")
          for s in ET.parse(sys.argv[1]).iter("testsuite") if s.get("name").startswith("gabarit-hil") for c in s.iter("testcase")}
alone = {}
for line in open(sys.argv[2], errors="replace"):
    try:
        d = json.loads(line)
    except ValueError:
        continue
    m = d.get("msg")
    if d.get("lvl") == "results" and isinstance(m, dict) and m.get("definition", "").startswith("gabarit-hil"):
        alone[(m["definition"], m["case"])] = m["result"]
print(f"lava-run {sys.argv[3]}: {len(alone)} verdicts; through the server: {len(server)}")
if int(sys.argv[3]) != 0 or not server or alone != server:
    print("FAIL: the verdicts differ:", sorted(set(alone.items()) ^ set(server.items()))[:10])
    sys.exit(1)
PY
exit $status
