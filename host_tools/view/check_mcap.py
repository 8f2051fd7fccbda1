#!/usr/bin/env python3
"""check_mcap.py FILE.mcap [--expect N] [--first-seq S] [--lcm-log FILE] [--images] - checks an
MCAP written by rigpose-view, decoded with PyPI `mcap` and `mcap-protobuf-support` (the
schemas come from the file itself, as Foxglove reads them):
  - the topics carry Foxglove's well-known schemas: /tf foxglove.FrameTransform, /rigpose/pose
    foxglove.PoseInFrame, /rigpose/trajectory foxglove.PosesInFrame, /rigpose/rig
    foxglove.SceneUpdate (and /rigpose/camK/image foxglove.RawImage, .../annotations
    foxglove.ImageAnnotations with --images, with the tracked features as points);
  - every pose is there as a world -> cam1 transform, in order: N of them (--expect), seq S,
    S+1, ... in /rigpose/pose_info, and with --lcm-log, each transform equal to the pose_t of the
    recording (position and quaternion, to 1e-12);
  - the last trajectory holds every pose (thinned only past --max-trajectory).
Prints one line per check and a closing "N passed, N failed"; exit 1 when any failed.
"""
import argparse
import json
import sys

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

WANT = {"/tf": "foxglove.FrameTransform", "/rigpose/pose": "foxglove.PoseInFrame",
        "/rigpose/trajectory": "foxglove.PosesInFrame", "/rigpose/rig": "foxglove.SceneUpdate"}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mcap")
    ap.add_argument("--expect", type=int, default=0)
    ap.add_argument("--first-seq", type=int, default=0, help="-1: any")
    ap.add_argument("--lcm-log")
    ap.add_argument("--images", action="store_true")
    a = ap.parse_args()
    passed, failed = [0], [0]

    def check(name, cond, detail=""):
        print("%s %s%s" % ("ok  " if cond else "FAIL", name, (": " + detail) if detail else ""))
        (passed if cond else failed)[0] += 1

    schemas, tfs, poses, infos, traj_len, images, anns = {}, [], 0, [], 0, {}, {}
    npts = [0]  # feature points drawn over all annotations
    with open(a.mcap, "rb") as f:
        reader = make_reader(f)
        factory, decoders = DecoderFactory(), {}
        for schema, channel, message in reader.iter_messages():
            t = channel.topic
            schemas[t] = schema.name if schema and schema.encoding == "protobuf" \
                else channel.message_encoding
            proto = None
            if channel.message_encoding == "protobuf":
                if channel.id not in decoders:
                    decoders[channel.id] = factory.decoder_for("protobuf", schema)
                proto = decoders[channel.id](message.data)
            if t == "/tf":
                if proto.parent_frame_id == "world":
                    tfs.append(proto)
            elif t == "/rigpose/pose":
                poses += 1
            elif t == "/rigpose/trajectory":
                traj_len = len(proto.poses)
            elif t == "/rigpose/pose_info":
                infos.append(json.loads(message.data))
            elif t.endswith("/image"):
                images[t] = images.get(t, 0) + 1
            elif t.endswith("/annotations"):
                anns[t] = anns.get(t, 0) + 1
                npts[0] += sum(len(p.points) for p in proto.points)
    want = dict(WANT)
    if a.images:
        for t in images:
            want[t] = "foxglove.RawImage"
            want[t.replace("/image", "/annotations")] = "foxglove.ImageAnnotations"
        check("camera images present", len(images) > 0, str(images))
        check("an annotation per image", all(anns.get(t.replace("/image", "/annotations")) == n
                                             for t, n in images.items()), str(anns))
        check("tracked features drawn: %d points" % npts[0], npts[0] > 0)
    for t, name in sorted(want.items()):
        check("topic %s has schema %s" % (t, name), schemas.get(t) == name,
              "" if schemas.get(t) == name else "found %s" % schemas.get(t))
    n = len(tfs)
    check("%d world -> cam1 transforms (expected %d)" % (n, a.expect),
          n == a.expect or (a.expect == 0 and n > 0))
    check("one PoseInFrame per transform", poses == n, "%d PoseInFrame" % poses)
    seqs = [i["seq"] for i in infos]
    if a.first_seq < 0 and seqs:
        a.first_seq = seqs[0]
    check("pose_info seq %d..%d in order, no gap" % (a.first_seq, a.first_seq + n - 1),
          seqs == list(range(a.first_seq, a.first_seq + n)),
          "" if seqs == list(range(a.first_seq, a.first_seq + n)) else "got %s..." % seqs[:5])
    check("every transform's child is cam1", all(tf.child_frame_id == "cam1" for tf in tfs))
    check("the last trajectory holds every pose", traj_len == n, "%d poses" % traj_len)
    if a.lcm_log:
        import lcm
        from rigpose import pose_t
        log = lcm.EventLog(a.lcm_log, "r")
        ref = [pose_t.decode(ev.data) for ev in log if ev.channel == "RIGPOSE_POSE"]
        log.close()
        worst = 0.0
        for tf, m in zip(tfs, ref):
            tr, q = tf.translation, tf.rotation
            worst = max([worst] + [abs(x - y) for x, y in zip((tr.x, tr.y, tr.z), m.position)]
                        + [abs(x - y) for x, y in zip((q.w, q.x, q.y, q.z), m.quaternion)])
        check("transforms equal the recording's %d poses, in order" % len(ref),
              len(ref) == n and worst < 1e-12, "largest difference %.3g" % worst)
    print("check_mcap: %d passed, %d failed" % (passed[0], failed[0]))
    return 1 if failed[0] else 0


if __name__ == "__main__":
    sys.exit(main())
