#!/usr/bin/env python3
"""Validates summary.json files against the engine's JSON Schema
(docs/summary.schema.json, draft 2020-12); prints every violation with its
path and exits 1 on any.
usage: validate_summary.py SCHEMA SUMMARY.json [SUMMARY.json ...]
"""

import json
import sys
from pathlib import Path

from jsonschema import Draft202012Validator


def main():
    schema = json.loads(Path(sys.argv[1]).read_text())
    Draft202012Validator.check_schema(schema)
    validator = Draft202012Validator(schema)
    failed = 0
    for name in sys.argv[2:]:
        summary = json.loads(Path(name).read_text())
        errors = sorted(validator.iter_errors(summary), key=lambda e: list(e.path))
        for e in errors:
            # an anyOf failure names its alternatives' own errors
            for c in e.context or [e]:
                where = "/".join(str(p) for p in [*e.path, *c.path])
                print(f"{name}: /{where}: {c.message[:300]}")
        failed += bool(errors)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
