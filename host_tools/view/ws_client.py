#!/usr/bin/env python3
"""ws_client.py --port P --expect N [--ready FILE] - a Foxglove WebSocket client (PyPI
`websockets`) for rigpose-view's live server on 127.0.0.1: reads the server's advertisements,
subscribes to /tf, /rigpose/pose and /rigpose/pose_info, touches --ready, then receives until N
poses came (60 s at most). Checks: the channels carry the schemas foxglove.FrameTransform and
foxglove.PoseInFrame (protobuf), N pose messages and N world -> cam1 transforms arrived, and the
pose_info seq numbers are consecutive. Exit 0 when all hold.
"""
import argparse
import json
import struct
import sys
import time

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

WANT = {"/tf": "foxglove.FrameTransform", "/rigpose/pose": "foxglove.PoseInFrame",
        "/rigpose/pose_info": None}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--expect", type=int, required=True)
    ap.add_argument("--ready")
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()

    uri = "ws://127.0.0.1:%d" % a.port
    for _ in range(100):  # the server may still be starting
        try:
            ws = connect(uri, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"],
                         open_timeout=2)
            break
        except OSError:
            time.sleep(0.1)
    else:
        print("FAIL: cannot connect to %s" % uri)
        return 1
    with ws:
        return session(ws, a)


def session(ws, a):
    subs, schema_of, counts, seqs = {}, {}, {t: 0 for t in WANT}, []
    next_id = [1]
    server = ["?"]

    def on_text(msg):
        m = json.loads(msg)
        if m.get("op") == "serverInfo":
            server[0] = m.get("name")
        if m.get("op") != "advertise":
            return
        new = []
        for ch in m["channels"]:
            if ch["topic"] in WANT and ch["topic"] not in subs.values():
                sid = next_id[0]
                next_id[0] += 1
                subs[sid] = ch["topic"]
                schema_of[ch["topic"]] = (ch.get("schemaName"), ch.get("encoding"))
                new.append({"id": sid, "channelId": ch["id"]})
        if new:
            ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))

    ready_at = time.monotonic() + 1.0
    deadline = time.monotonic() + a.timeout
    while time.monotonic() < deadline and counts["/rigpose/pose_info"] < a.expect:
        if a.ready and len(subs) == len(WANT) and time.monotonic() > ready_at:
            open(a.ready, "w").close()
            a.ready = None
        try:
            msg = ws.recv(timeout=0.2)
        except TimeoutError:
            continue
        except ConnectionClosed:
            print("ws_client: the server closed the connection")
            break
        if isinstance(msg, str):
            on_text(msg)
            continue
        if msg[0] != 0x01:  # message data: op, subscription id, log time, payload
            continue
        sid, _t = struct.unpack_from("<IQ", msg, 1)
        topic = subs.get(sid)
        if topic is None:
            continue
        counts[topic] += 1
        if topic == "/rigpose/pose_info":
            seqs.append(json.loads(msg[13:])["seq"])

    print("ws_client: server %s; subscribed %s; received %s" % (server[0], sorted(schema_of),
                                                                counts))
    problems = []
    for t, name in WANT.items():
        if name and schema_of.get(t) != (name, "protobuf"):
            problems.append("%s advertised as %s" % (t, schema_of.get(t)))
    if counts["/rigpose/pose"] < a.expect or counts["/rigpose/pose_info"] < a.expect:
        problems.append("only %d poses" % counts["/rigpose/pose"])
    if counts["/tf"] < a.expect:
        problems.append("only %d transforms" % counts["/tf"])
    if seqs and seqs != list(range(seqs[0], seqs[0] + len(seqs))):
        problems.append("pose seq not consecutive: %s..." % seqs[:8])
    for p in problems:
        print("FAIL:", p)
    if not problems:
        print("ws_client: ok, %d poses, seq %d..%d" % (len(seqs), seqs[0], seqs[-1]))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
