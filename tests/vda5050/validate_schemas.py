#!/usr/bin/env python3
"""Runs write_samples and validates every message it writes against the VDA 5050 schemas.

usage: validate_schemas.py WRITE_SAMPLES SCHEMA_ROOT [SEN3BOT_SCHEMAS]

SCHEMA_ROOT holds one directory per version (2.1.0/, and 2.0.0/ when its schemas are there).
A version without its own schemas is checked against the nearest one that has them, plus a
check that none of the members added after it appear. With SEN3BOT_SCHEMAS, Sen3Bot's own
messages (people, advisory, formation) are checked against SEN3BOT_SCHEMAS/TOPIC.schema.json.
Exits non-zero on any failure.
"""
import json
import os
import subprocess
import sys
import tempfile

import jsonschema

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from validate_messages import ADDED_IN_2_1, SEN3BOT_TOPICS, keys  # noqa: E402  (one list of each)
from validate_messages import validator as schema_validator  # noqa: E402

TOPICS = ["order", "instantActions", "state", "connection", "visualization", "factsheet"]
VERSIONS = ["2.0.0", "2.1.0"]


def main():
    if len(sys.argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        return 2
    writer, schema_root = sys.argv[1], sys.argv[2]
    sen3bot_schemas = sys.argv[3] if len(sys.argv) == 4 else None
    failures = []
    checked = 0
    with tempfile.TemporaryDirectory() as out:
        for v in VERSIONS:
            os.mkdir(os.path.join(out, v))
        if sen3bot_schemas:
            os.mkdir(os.path.join(out, "sen3bot"))
        subprocess.run([writer, out], check=True)
        for topic in sorted(SEN3BOT_TOPICS) if sen3bot_schemas else []:
            with open(os.path.join(out, "sen3bot", topic + ".json"), encoding="utf-8") as f:
                message = json.load(f)
            errors = list(schema_validator(os.path.join(sen3bot_schemas, topic + ".schema.json")).iter_errors(message))
            for e in errors:
                failures.append(f"sen3bot/{topic}: {'/'.join(map(str, e.path)) or '(root)'}: {e.message}")
            checked += 1
            print(f"sen3bot/{topic}: {'FAIL' if errors else 'ok'}")
        for v in VERSIONS:
            schema_dir = os.path.join(schema_root, v)
            if not os.path.isdir(schema_dir):
                schema_dir = os.path.join(schema_root, "2.1.0")
            for topic in TOPICS:
                path = os.path.join(out, v, topic + ".json")
                with open(path, encoding="utf-8") as f:
                    message = json.load(f)
                with open(os.path.join(schema_dir, topic + ".schema"), encoding="utf-8") as f:
                    schema = json.load(f)
                cls = jsonschema.validators.validator_for(schema)
                cls.check_schema(schema)
                validator = cls(schema, format_checker=jsonschema.FormatChecker())
                errors = sorted(validator.iter_errors(message), key=lambda e: list(e.path))
                for e in errors:
                    failures.append(f"{v}/{topic}: {'/'.join(map(str, e.path)) or '(root)'}: {e.message}")
                if message.get("version", v) != v:
                    failures.append(f"{v}/{topic}: header version {message.get('version')}")
                if v == "2.0.0":
                    extra = ADDED_IN_2_1.intersection(keys(message))
                    if extra:
                        failures.append(f"{v}/{topic}: 2.1.0 members in a 2.0.0 message: {sorted(extra)}")
                checked += 1
                print(f"{v}/{topic}: {'FAIL' if errors else 'ok'} (schema {os.path.basename(schema_dir)})")
    if failures:
        print("\n".join(["SCHEMA VALIDATION FAILED:"] + failures), file=sys.stderr)
        return 1
    print(f"{checked} messages valid")
    return 0


if __name__ == "__main__":
    sys.exit(main())
