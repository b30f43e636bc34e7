#!/usr/bin/env python3
"""Checks tetherbot's Foxglove output with readers nobody on the team wrote (issue 23, item 2).

    foxglove_check.py mcap FILE.mcap EXPECTED.json
        Reads the MCAP with the `mcap` library, decodes every protobuf message with Foxglove's published
        classes (`foxglove-schemas-protobuf`) after checking that the schema in the file is the published one,
        validates every JSON series message against its JSON schema (`jsonschema`), compares the raw wire
        channels and the rover's pose estimates with the field log (EXPECTED.json and the .bin files beside it,
        written by host-sim/tests/foxglove.rs from the field log), and the true poses with the mission's JSON
        summary.

    foxglove_check.py live -- COMMAND...
        Runs COMMAND (a `tetherbot mission --live 127.0.0.1:0 ...`), reads the `live view: ws://...` line,
        subscribes to every advertised channel with the `websockets` client, decodes every message it receives
        with the published schemas, and checks that the scene arrived.

Exit 0 when every check passed; the last line is `N passed, N failed`.
"""

import asyncio
import base64
import json
import math
import subprocess
import sys
import threading

import foxglove_schemas_protobuf  # noqa: F401  (the published schemas)
import jsonschema
from google.protobuf import descriptor_pb2
from mcap.reader import make_reader

import importlib

PROTOBUF_TOPICS = {
    "/tf": "foxglove.FrameTransforms",
    "/scans": "foxglove.PointCloud",
    "/scene/wire": "foxglove.SceneUpdate",
    "/scene/truth": "foxglove.SceneUpdate",
    "/log": "foxglove.Log",
}
SERIES_TOPICS = {
    "/tether/reading": "tetherbot.TetherReading",
    "/mission/status": "tetherbot.MissionStatus",
    "/telemetry": "tetherbot.Telemetry",
    "/truth/series": "tetherbot.Truth",
}
RAW_TOPICS = {"/link/host_to_flight": "h2f", "/link/flight_to_host": "f2h"}
FRAME_TOPICS = {"/frames/host_to_flight": "h2f", "/frames/flight_to_host": "f2h"}


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, ok, what):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
            print(f"FAIL: {what}")
        return ok

    def close(self):
        print(f"{self.passed} passed, {self.failed} failed")
        return 0 if self.failed == 0 else 1


def published_class(schema_name):
    """The class `foxglove-schemas-protobuf` publishes for `foxglove.Name`."""
    short = schema_name.split(".", 1)[1]
    module = importlib.import_module(f"foxglove_schemas_protobuf.{short}_pb2")
    return getattr(module, short)


def embedded_matches_published(schema_name, fds_bytes):
    """Whether the FileDescriptorSet in the file describes the message as the published class does (every
    message type it uses, field by field)."""
    fds = descriptor_pb2.FileDescriptorSet.FromString(fds_bytes)
    embedded = {}
    for f in fds.file:
        for m in f.message_type:
            embedded[f"{f.package}.{m.name}"] = m
    todo = [published_class(schema_name).DESCRIPTOR]
    seen = set()
    while todo:
        d = todo.pop()
        if d.full_name in seen:
            continue
        seen.add(d.full_name)
        published = descriptor_pb2.DescriptorProto()
        d.CopyToProto(published)
        got = embedded.get(d.full_name)
        if got is None:
            return False, f"{d.full_name} missing from the file's schema"
        want_fields = sorted((f.number, f.name, f.type, f.label) for f in published.field)
        got_fields = sorted((f.number, f.name, f.type, f.label) for f in got.field)
        if want_fields != got_fields:
            return False, f"{d.full_name}: fields differ: file {got_fields} published {want_fields}"
        todo.extend(f.message_type for f in d.fields if f.message_type is not None)
    return True, ""


def decode_published(schema_name, data):
    msg = published_class(schema_name)()
    msg.ParseFromString(data)
    return msg


def close_to(a, b, tol=1e-6):
    return all(math.isfinite(x) and abs(x - y) <= tol * max(1.0, abs(y)) for x, y in zip(a, b)) and len(a) == len(b)


def check_mcap(path, expected_path):
    c = Checks()
    with open(expected_path) as f:
        exp = json.load(f)
    base = expected_path.rsplit(".", 1)[0]
    raw_expected = {}
    for side in ("h2f", "f2h"):
        with open(f"{base}-{side}.bin", "rb") as f:
            raw_expected[side] = f.read()
    with open(exp["summary"]) as f:
        summary = json.load(f)

    with open(path, "rb") as f:
        reader = make_reader(f)
        summ = reader.get_summary()
        channels = {ch.id: ch for ch in summ.channels.values()}
        schemas = summ.schemas
        topics = {ch.topic for ch in channels.values()}
        want_topics = set(PROTOBUF_TOPICS) | set(SERIES_TOPICS) | set(RAW_TOPICS) | set(FRAME_TOPICS)
        if exp.get("log_frames", 0) == 0:
            want_topics.discard("/log")
        c.check(topics == want_topics, f"channels: got {sorted(topics)}, want {sorted(want_topics)}")
        meta = list(reader.iter_metadata())
        c.check(any(m.name == "tetherbot-field-log" and m.metadata.get("seed") == str(exp["seed"]) for m in meta),
                f"field-log metadata with seed {exp['seed']}: {[(m.name, m.metadata.get('seed')) for m in meta]}")

        validators = {}
        for ch in channels.values():
            schema = schemas.get(ch.schema_id)
            if ch.topic in PROTOBUF_TOPICS:
                want = PROTOBUF_TOPICS[ch.topic]
                ok = c.check(schema is not None and schema.name == want and schema.encoding == "protobuf"
                             and ch.message_encoding == "protobuf",
                             f"{ch.topic}: schema {schema and (schema.name, schema.encoding)} encoding "
                             f"{ch.message_encoding}, want {want} protobuf")
                if ok:
                    same, why = embedded_matches_published(want, schema.data)
                    c.check(same, f"{ch.topic}: the file's schema is not the published {want}: {why}")
            elif ch.topic in SERIES_TOPICS:
                ok = c.check(schema is not None and schema.name == SERIES_TOPICS[ch.topic]
                             and schema.encoding == "jsonschema" and ch.message_encoding == "json",
                             f"{ch.topic}: schema {schema and (schema.name, schema.encoding)}")
                if ok:
                    s = json.loads(schema.data)
                    jsonschema.Draft202012Validator.check_schema(s)
                    validators[ch.id] = jsonschema.Draft202012Validator(s)
            elif ch.topic in RAW_TOPICS:
                c.check(ch.schema_id == 0 and ch.message_encoding == "tetherbot-wire-v1", f"{ch.topic}: raw channel")
            elif ch.topic in FRAME_TOPICS:
                c.check(ch.schema_id == 0 and ch.message_encoding == "json", f"{ch.topic}: schemaless JSON")

        counts = {}
        raw_got = {"h2f": bytearray(), "f2h": bytearray()}
        frames = {"h2f": 0, "f2h": 0}
        bad_frames = 0
        rover_tf, sensor_tf, true_tf = [], [], []
        bad_parents = 0
        bad_clouds = []
        bad_triangles = 0
        scan_points = 0
        clouds = 0
        wire_entities = {}
        truth_entities = {}
        logs = []
        series_bad = 0
        undecoded = 0
        for schema, ch, msg in reader.iter_messages():
            counts[ch.topic] = counts.get(ch.topic, 0) + 1
            if ch.topic in RAW_TOPICS:
                raw_got[RAW_TOPICS[ch.topic]] += msg.data
            elif ch.topic in FRAME_TOPICS:
                v = json.loads(msg.data)
                frames[FRAME_TOPICS[ch.topic]] += 1
                bad_frames += "error" in v
            elif ch.topic in SERIES_TOPICS:
                v = json.loads(msg.data)
                if ch.id in validators and not validators[ch.id].is_valid(v):
                    series_bad += 1
            elif ch.topic in PROTOBUF_TOPICS:
                try:
                    m = decode_published(PROTOBUF_TOPICS[ch.topic], msg.data)
                except Exception as e:  # noqa: BLE001  (any decode failure is a failed check)
                    undecoded += 1
                    print(f"{ch.topic}: does not decode: {e}")
                    continue
                if ch.topic == "/tf":
                    for t in m.transforms:
                        row = [msg.log_time, t.translation.x, t.translation.y, t.translation.z,
                               t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]
                        bad_parents += t.parent_frame_id != "world"
                        {"rover": rover_tf, "sensor": sensor_tf, "rover_true": true_tf}.setdefault(
                            t.child_frame_id, []).append(row)
                elif ch.topic == "/scans":
                    clouds += 1
                    names = [(f.name, f.offset, f.type) for f in m.fields]
                    ok = names[:3] == [("x", 0, 7), ("y", 4, 7), ("z", 8, 7)] and m.point_stride == 12
                    ok = ok and len(m.data) % 12 == 0
                    if not ok:
                        bad_clouds.append((names, m.point_stride, len(m.data)))
                    scan_points += len(m.data) // 12
                elif ch.topic.startswith("/scene/"):
                    into = wire_entities if ch.topic == "/scene/wire" else truth_entities
                    for e in m.entities:
                        into[e.id] = into.get(e.id, 0) + 1
                        for tri in e.triangles:
                            n = len(tri.points)
                            bad_triangles += not (len(tri.indices) % 3 == 0 and all(i < n for i in tri.indices))
                elif ch.topic == "/log":
                    logs.append(m)

    c.check(undecoded == 0, f"{undecoded} protobuf messages did not decode with the published schemas")
    c.check(not bad_clouds, f"/scans: clouds not x, y, z float32 with stride 12: {bad_clouds[:3]}")
    c.check(bad_triangles == 0, f"{bad_triangles} triangle lists with bad indices")
    c.check(bad_parents == 0, f"{bad_parents} transforms whose parent is not world")
    c.check(series_bad == 0, f"{series_bad} series messages do not match their JSON schema")
    for side, topic in (("h2f", "/link/host_to_flight"), ("f2h", "/link/flight_to_host")):
        c.check(counts.get(topic, 0) == exp["records"][side], f"{topic}: {counts.get(topic, 0)} records, "
                f"field log {exp['records'][side]}")
        c.check(bytes(raw_got[side]) == raw_expected[side], f"{topic}: bytes differ from the field log's")
        c.check(frames[side] == exp["frames"][side], f"frames {side}: {frames[side]}, field log {exp['frames'][side]}")
    c.check(bad_frames == exp["bad_frames"], f"undecodable frames {bad_frames}, field log {exp['bad_frames']}")
    for topic, key in (("/tether/reading", "tether_readings"), ("/mission/status", "mission_status"),
                       ("/telemetry", "telemetry"), ("/log", "log_frames")):
        c.check(counts.get(topic, 0) == exp[key], f"{topic}: {counts.get(topic, 0)} messages, field log {exp[key]}")
    c.check(clouds == exp["scans"] and len(sensor_tf) == exp["scans"],
            f"/scans: {clouds} clouds, {len(sensor_tf)} sensor transforms, field log {exp['scans']} complete scans")
    c.check(scan_points == exp["scan_points"], f"/scans: {scan_points} points, field log {exp['scan_points']}")
    c.check(wire_entities.get("plan/0", 0) == 1 and len([k for k in wire_entities if k.startswith("plan/")]) == exp["plans"],
            f"plans drawn {sorted(k for k in wire_entities if k.startswith('plan/'))}, field log {exp['plans']}")
    c.check(wire_entities.get("root_anchor") == 1 and wire_entities.get("goal") == 1, f"wire entities {wire_entities}")

    # the rover's pose estimates, one transform per MotionReport, against the field log
    want = exp["poses"]
    c.check(len(rover_tf) == len(want), f"/tf rover: {len(rover_tf)} transforms, field log {len(want)} MotionReports")
    wrong = [(g, w) for g, w in zip(rover_tf, want) if g[0] != w[0] or not close_to(g[1:], w[1:])]
    c.check(not wrong, f"/tf rover: {len(wrong)} poses differ from the field log, first {wrong[:1]}")
    # the true poses against the mission's JSON summary (its trace)
    trace = summary["trace"]
    c.check(len(true_tf) == len(trace) > 0, f"/tf rover_true: {len(true_tf)} transforms, summary {len(trace)}")
    wrong = [(g, t) for g, t in zip(true_tf, trace)
             if g[0] != round(t["t_s"] * 1e9) or not close_to(g[1:4], t["axle"])
             or not math.isclose(sum(q * q for q in g[4:]), 1.0, rel_tol=1e-5)]
    c.check(not wrong, f"/tf rover_true: {len(wrong)} differ from the summary's trace, first {wrong[:1]}")
    c.check(counts.get("/truth/series", 0) == len(trace), f"/truth/series {counts.get('/truth/series', 0)}")
    c.check({"terrain", "rocks", "true_tether", "true_path", "rover_true_body"} <= set(truth_entities),
            f"truth entities {sorted(truth_entities)}")
    c.check(truth_entities.get("true_tether") == exp["tether_snapshots"],
            f"true tether snapshots {truth_entities.get('true_tether')}, summary {exp['tether_snapshots']}")
    if "layout" in exp:
        # a run without flight log frames has no /log channel (the SDK writes a channel with its first message)
        quiet = {"/log"} if exp.get("log_frames", 0) == 0 else set()
        check_layout(c, exp["layout"], topics | quiet, {ch.topic: json.loads(schemas[ch.schema_id].data)
                                                for ch in channels.values() if ch.topic in SERIES_TOPICS})
    print(f"{path}: {sum(counts.values())} messages on {len(counts)} channels decoded; "
          f"{len(rover_tf)} pose estimates, {len(true_tf)} true poses, {clouds} scans ({scan_points} points), "
          f"{len(logs)} flight logs")
    return c.close()


def check_layout(c, layout_path, topics, series_schemas):
    """Every topic the shipped Foxglove layout shows is a channel of the file, every plotted field a field of
    its series' JSON schema."""
    with open(layout_path) as f:
        layout = json.load(f)
    for panel, cfg in layout["configById"].items():
        for t in cfg.get("topics", {}):
            c.check(t in topics, f"layout {panel}: topic {t} is not a channel")
        paths = [p["value"] for p in cfg.get("paths", [])]
        for key in ("topicPath", "topicToRender"):
            if key in cfg:
                c.check(cfg[key] in topics, f"layout {panel}: {cfg[key]} is not a channel")
        for value in paths:
            t, field = value.rsplit(".", 1)
            ok = t in series_schemas and field in series_schemas[t]["properties"]
            c.check(ok, f"layout {panel}: {value} is not a field of a series channel")
    names = set(layout["configById"])
    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])
    c.check(set(leaves(layout["layout"])) == names, f"layout tree {leaves(layout['layout'])} vs panels {names}")


async def live_client(url, over, c):
    import websockets

    got = {}
    subs = {}
    validators = {}
    undecoded = 0
    async with websockets.connect(url, subprotocols=["foxglove.sdk.v1"], max_size=None) as ws:
        next_id = 1
        while True:
            try:
                raw = await asyncio.wait_for(ws.recv(), timeout=1.0)
            except asyncio.TimeoutError:
                if over.is_set():
                    break
                continue
            except websockets.ConnectionClosed:
                break
            if isinstance(raw, str):
                m = json.loads(raw)
                if m.get("op") == "advertise":
                    want = []
                    for ch in m["channels"]:
                        subs[next_id] = ch
                        want.append({"id": next_id, "channelId": ch["id"]})
                        next_id += 1
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": want}))
                continue
            if raw[0] != 1:
                continue
            sub = int.from_bytes(raw[1:5], "little")
            data = raw[13:]
            ch = subs.get(sub)
            if ch is None:
                continue
            topic = ch["topic"]
            try:
                if ch["encoding"] == "protobuf":
                    name = ch["schemaName"]
                    fds = base64.b64decode(ch["schema"])
                    if topic not in got:
                        same, why = embedded_matches_published(name, fds)
                        c.check(same, f"live {topic}: advertised schema is not the published {name}: {why}")
                    msg = decode_published(name, data)
                    if topic == "/scene/truth":
                        for e in msg.entities:
                            got[f"entity:{e.id}"] = got.get(f"entity:{e.id}", 0) + 1
                    if topic == "/tf":
                        for t in msg.transforms:
                            got[f"tf:{t.child_frame_id}"] = got.get(f"tf:{t.child_frame_id}", 0) + 1
                elif ch["encoding"] == "json":
                    v = json.loads(data)
                    if ch.get("schemaEncoding") == "jsonschema" and ch.get("schema"):
                        if sub not in validators:
                            validators[sub] = jsonschema.Draft202012Validator(json.loads(ch["schema"]))
                        if not validators[sub].is_valid(v):
                            raise ValueError(f"{v} does not match its JSON schema")
            except Exception as e:  # noqa: BLE001
                undecoded += 1
                print(f"live {topic}: does not decode: {e}")
                continue
            got[topic] = got.get(topic, 0) + 1
    return got, undecoded


def check_live(cmd):
    c = Checks()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    url = None
    for line in proc.stdout:
        print(line, end="")
        if line.startswith("live view: "):
            url = line.split()[2]
            break
    if not c.check(url is not None, "no `live view: ws://...` line"):
        proc.kill()
        return c.close()
    over = threading.Event()

    def watch():
        for line in proc.stdout:
            print(line, end="")
            if "mission over" in line:
                over.set()
        over.set()

    threading.Thread(target=watch, daemon=True).start()
    got, undecoded = asyncio.run(live_client(url, over, c))
    code = proc.wait(timeout=600)
    c.check(code == 0, f"the mission exited {code}")
    c.check(undecoded == 0, f"{undecoded} live messages did not decode")
    for key in ("/tf", "/scans", "/scene/wire", "/scene/truth", "/link/host_to_flight", "/link/flight_to_host",
                "/mission/status", "/tether/reading", "tf:rover", "tf:sensor", "tf:rover_true", "entity:terrain",
                "entity:true_tether"):
        c.check(got.get(key, 0) > 0, f"live: nothing received for {key}")
    print(f"live: received {sum(v for k, v in got.items() if k.startswith('/'))} messages: "
          + ", ".join(f"{k} {v}" for k, v in sorted(got.items())))
    return c.close()


def main(argv):
    if len(argv) == 4 and argv[1] == "mcap":
        return check_mcap(argv[2], argv[3])
    if len(argv) > 3 and argv[1] == "live" and argv[2] == "--":
        return check_live(argv[3:])
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
