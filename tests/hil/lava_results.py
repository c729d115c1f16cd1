#!/usr/bin/env python3
"""Checks a LAVA job's outcome as lava_run_test.sh left it in JOB/: lava-run's
exit status (JOB/status), its log's results (JOB/lava.log: JSON lines; the
gabarit-hil-frames and gabarit-hil-checks test cases, the job's own result)
and the harness's report (JOB/report)."""
import argparse
import json
import pathlib
import sys


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("job", type=pathlib.Path)
    p.add_argument("--frames", type=int, help="frame cases expected (pass, or skip)")
    p.add_argument("--skipped", default="", help="the frame cases expected to skip, comma-separated")
    p.add_argument("--checks-pass", action="store_true", help="every check case passes")
    p.add_argument("--failed-check", help="a check case expected to fail (the job still completes)")
    p.add_argument("--failed-frame", help="the one frame case expected to fail (the job still completes)")
    p.add_argument("--incomplete", metavar="ERROR_TYPE", help="the job is incomplete with this error type")
    p.add_argument("--report-error", help="text the report's error must hold")
    a = p.parse_args()
    status = int((a.job / "status").read_text())
    cases, job = {}, {}
    for line in open(a.job / "lava.log", errors="replace"):
        try:
            d = json.loads(line)
        except ValueError:
            continue
        m = d.get("msg")
        if d.get("lvl") != "results" or not isinstance(m, dict):
            continue
        if m.get("definition", "").startswith("gabarit-hil"):
            cases[(m["definition"], m["case"])] = (m["result"], m.get("measurement"), m.get("units"))
        if m.get("definition") == "lava" and m.get("case") == "job":
            job = m
    frames = {c: r for (d, c), r in cases.items() if d == "gabarit-hil-frames"}
    checks = {c: r[0] for (d, c), r in cases.items() if d == "gabarit-hil-checks"}
    skips = sorted(c for c, r in frames.items() if r[0] == "skip")
    errors = sorted(float(r[1]) for r in frames.values() if r[0] == "pass" and r[2] == "px")
    median = errors[len(errors) // 2] if errors else float("nan")
    problems = []
    if a.incomplete:
        if status == 0 or job.get("result") != "fail" or job.get("error_type") != a.incomplete:
            problems.append(f"want an incomplete job ({a.incomplete}): lava-run {status}, {job}")
    else:
        if status != 0 or job.get("result") != "pass":
            problems.append(f"want a complete job: lava-run {status}, {job}")
        if len(frames) != a.frames:
            problems.append(f"{len(frames)} frame cases, want {a.frames}")
        want_skips = sorted(s for s in a.skipped.split(",") if s)
        if skips != want_skips:
            problems.append(f"skipped frames {skips}, want {want_skips}")
        failed = sorted(c for c, r in frames.items() if r[0] not in ("pass", "skip"))
        if failed != ([a.failed_frame] if a.failed_frame else []):
            problems.append(f"failed frames {failed}, want {a.failed_frame or 'none'}")
        if a.failed_frame and (frames.get(a.failed_frame, ("", None, ""))[2] != "px"):
            problems.append(f"the failed frame {a.failed_frame} has no position error: {frames.get(a.failed_frame)}")
        passed = len(want_skips) + (1 if a.failed_frame else 0)
        if a.frames and (len(errors) != a.frames - passed or median > 0.1):
            problems.append(f"the frames' errors against gt.csv: {errors}")
        if len(checks) < 8:
            problems.append(f"{len(checks)} check cases")
        if a.checks_pass and any(r != "pass" for r in checks.values()):
            problems.append(f"checks: {checks}")
        if a.failed_check and checks.get(a.failed_check) != "fail":
            problems.append(f"the {a.failed_check} case: {checks.get(a.failed_check)}, want fail")
    summary_path = a.job / "report" / "summary.json"
    if a.incomplete != "Infrastructure":  # a board that never boots never starts the replayer
        if not summary_path.exists() or not (a.job / "report" / "junit.xml").exists():
            problems.append("no report in the job's folder")
        elif a.report_error and a.report_error not in json.loads(summary_path.read_text()).get("error", ""):
            problems.append(f"the report's error does not say '{a.report_error}'")
    print(f"{a.job.name}: lava-run {status}, job {job.get('result')} {job.get('error_type', '')}: {len(frames)} frame cases"
          f" ({len(skips)} skipped, median error {median:.3f} px), {len(checks)} check cases"
          f" ({sum(r != 'pass' for r in checks.values())} failed)")
    if a.failed_frame and a.failed_frame in frames:
        result, measurement, units = frames[a.failed_frame]
        print(f"{a.job.name}: {a.failed_frame} {result}, its error against gt.csv {measurement} {units}")
    for problem in problems:
        print("FAIL:", problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
