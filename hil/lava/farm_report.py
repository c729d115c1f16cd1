#!/usr/bin/env python3
"""Merges the JUnit of LAVA jobs into one report that names each case's board
(docs/hil-farm.md): for each job, its device and state from the server's API
(/api/v0.2/jobs/ID/) and its JUnit (/api/v0.2/jobs/ID/junit/); each test
suite is renamed BOARD.SUITE, with the job's id, device, state and health as
properties.

  farm_report.py --url http://SERVER --token TOKEN --out merged.xml [--collect DIR] JOB_ID...

Prints one line per job and per failed case (board, job, suite, case), and
exits 1 if a job is not Complete or a case failed.

With --collect, each job's harness report (JUnit, CSV, Markdown, summary.json),
which `gabarit hil lava-replay` wrote into the job's folder on the worker (the
job's context gabarit_bundle, on storage the worker and this machine share),
is copied into DIR/BOARD-jobID/: LAVA 2023.01 keeps a job's log and test cases
but has no store for a file a command on the worker wrote.
"""
import argparse
import json
import pathlib
import shutil
import sys
import urllib.request
import xml.etree.ElementTree as ET

import yaml


def get(url: str, token: str) -> bytes:
    request = urllib.request.Request(url, headers={"Authorization": f"Token {token}"})
    with urllib.request.urlopen(request, timeout=60) as response:
        return response.read()


def collect_report(job: dict, board: str, job_id: int, into: pathlib.Path) -> bool:
    """Copies the job's harness report; False (and says why) when it has none."""
    try:
        context = (yaml.safe_load(job.get("definition") or "") or {}).get("context") or {}
    except yaml.YAMLError:
        context = {}
    bundle = context.get("gabarit_bundle")
    report = pathlib.Path(bundle) / "report" if bundle else None
    if report is None or not (report / "summary.json").is_file():
        print(f"  NO REPORT {board} job {job_id}: {report or 'no gabarit_bundle in its context'}")
        return False
    target = into / f"{board}-job{job_id}"
    shutil.copytree(report, target)
    print(f"  report {board} job {job_id}: {target}")
    return True


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--url", required=True, help="the server, e.g. http://127.0.0.1:8000")
    p.add_argument("--token", required=True, help="an API token of a user who may see the jobs")
    p.add_argument("--out", required=True, help="the merged JUnit XML")
    p.add_argument("--collect", type=pathlib.Path, metavar="DIR",
                   help="copy each job's harness report into DIR/BOARD-jobID (a new or empty folder)")
    p.add_argument("jobs", nargs="+", type=int)
    a = p.parse_args()
    if a.collect and a.collect.exists() and (not a.collect.is_dir() or any(a.collect.iterdir())):
        p.error(f"--collect {a.collect}: exists and is not an empty folder")
    api = a.url.rstrip("/") + "/api/v0.2/jobs/"
    merged = ET.Element("testsuites")
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    bad = 0
    for job_id in a.jobs:
        job = json.loads(get(f"{api}{job_id}/", a.token))
        board, health = job.get("actual_device") or "(no device)", job.get("health")
        junit = ET.fromstring(get(f"{api}{job_id}/junit/", a.token))
        failed_cases = []
        for suite in junit.iter("testsuite"):
            name = suite.get("name")
            suite.set("name", f"{board}.{name}")
            properties = ET.SubElement(suite, "properties")
            for key, value in (("job", job_id), ("device", board), ("state", job.get("state")), ("health", health)):
                ET.SubElement(properties, "property", name=key, value=str(value))
            for key in totals:
                totals[key] += int(suite.get(key, 0) or 0)
            for case in suite.iter("testcase"):
                if case.find("failure") is not None or case.find("error") is not None:
                    failed_cases.append(f"{name}.{case.get('name')}")
            merged.append(suite)
        print(f"job {job_id} on {board}: {job.get('state')}, {health}, {len(failed_cases)} failed cases")
        for case in failed_cases:
            print(f"  FAILED {board} job {job_id}: {case}")
        if a.collect:
            bad += not collect_report(job, board, job_id, a.collect)
        bad += health != "Complete" or bool(failed_cases)
    for key, value in totals.items():
        merged.set(key, str(value))
    ET.ElementTree(merged).write(a.out, encoding="utf-8", xml_declaration=True)
    print(f"{a.out}: {len(a.jobs)} jobs, {totals['tests']} cases, {totals['failures']} failures, {totals['errors']} errors")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
