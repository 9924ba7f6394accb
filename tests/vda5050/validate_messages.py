#!/usr/bin/env python3
"""Validates captured fleet messages against the shipped schemas.

usage: validate_messages.py DIR VERSION SCHEMA_ROOT SEN3BOT_SCHEMAS

DIR holds one file per message, named TOPIC.N.json, TOPIC being the last level of the MQTT
topic (state, connection, visualization, factsheet, order, instantActions) or one of Sen3Bot's
own ("people", "advisory", "formation"). VDA 5050 messages are checked against SCHEMA_ROOT/VERSION (or
2.1.0's schemas when VERSION has none shipped, plus a check that no member added in 2.1
appears), Sen3Bot's against SEN3BOT_SCHEMAS/TOPIC.schema.json. Exits non-zero when any message
fails, listing every failure.
"""
import json
import os
import sys

import jsonschema

ADDED_IN_2_1 = {"corridor", "maps", "vehicleConfig", "blockingTypes"}
SEN3BOT_TOPICS = {"people", "advisory", "formation"}


def keys(value):
    if isinstance(value, dict):
        for k, v in value.items():
            yield k
            yield from keys(v)
    elif isinstance(value, list):
        for v in value:
            yield from keys(v)


def validator(path):
    with open(path, encoding="utf-8") as f:
        schema = json.load(f)
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    return cls(schema, format_checker=jsonschema.FormatChecker())


def main():
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        return 2
    folder, version, schema_root, sen3bot_schemas = sys.argv[1:]
    schema_dir = os.path.join(schema_root, version)
    if not os.path.isdir(schema_dir):
        schema_dir = os.path.join(schema_root, "2.1.0")
    validators = {}
    failures = []
    counts = {}
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".json"):
            continue
        topic = name.split(".")[0]
        if topic not in validators:
            path = (os.path.join(sen3bot_schemas, topic + ".schema.json") if topic in SEN3BOT_TOPICS
                    else os.path.join(schema_dir, topic + ".schema"))
            if not os.path.exists(path):
                failures.append(f"{name}: no schema for topic '{topic}'")
                continue
            validators[topic] = validator(path)
        with open(os.path.join(folder, name), encoding="utf-8") as f:
            try:
                message = json.load(f)
            except json.JSONDecodeError as e:
                failures.append(f"{name}: not JSON: {e}")
                continue
        counts[topic] = counts.get(topic, 0) + 1
        for e in validators[topic].iter_errors(message):
            failures.append(f"{name}: {'/'.join(map(str, e.path)) or '(root)'}: {e.message}")
        if topic not in SEN3BOT_TOPICS:
            if message.get("version", "")[:4] != version[:4]:
                failures.append(f"{name}: version {message.get('version')!r}, the site speaks {version}")
            if version.startswith("2.0"):
                for k in sorted(ADDED_IN_2_1.intersection(keys(message))):
                    failures.append(f"{name}: '{k}' is not in VDA 5050 2.0")
    for f in failures:
        print(f, file=sys.stderr)
    summary = ", ".join(f"{n} {t}" for t, n in sorted(counts.items()))
    print(f"validate_messages: {sum(counts.values())} messages ({summary}), {len(failures)} failures")
    return 1 if failures or not counts else 0


if __name__ == "__main__":
    sys.exit(main())
