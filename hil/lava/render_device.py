#!/usr/bin/env python3
"""Renders a LAVA device dictionary against hil/lava's device types, as a LAVA
server does, for `lava-run` on a machine without a server (docs/hil-farm.md).

  render_device.py DICTIONARY.jinja2 [--context NAME=VALUE ...] > device.yaml

The dictionary extends one of the device types beside this script; a job's
context (e.g. gabarit_bundle) is passed with --context, as the server passes it.
"""
import argparse
import pathlib
import sys

import jinja2
import yaml


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dictionary", type=pathlib.Path)
    parser.add_argument("--context", action="append", default=[], metavar="NAME=VALUE")
    args = parser.parse_args()
    context = {}
    for item in args.context:
        name, sep, value = item.partition("=")
        if not sep or not name.isidentifier():
            parser.error(f"--context {item}: want NAME=VALUE")
        context[name] = value
    here = pathlib.Path(__file__).resolve().parent
    env = jinja2.Environment(loader=jinja2.FileSystemLoader([str(args.dictionary.resolve().parent), str(here)]),
                             undefined=jinja2.StrictUndefined, autoescape=False)
    try:
        text = env.get_template(args.dictionary.name).render(**context)
        yaml.safe_load(text)  # a device dictionary must render to YAML
    except (jinja2.TemplateError, yaml.YAMLError) as e:
        print(f"{args.dictionary}: {e}", file=sys.stderr)
        return 1
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
