#!/usr/bin/env python3
"""rigpose-view - the rigpose daemon's LCM channels in Foxglove.

Subscribes to the daemon's pose, status and (when on) image channels and either serves them
live over Foxglove's WebSocket protocol on this machine only (127.0.0.1; open
ws://127.0.0.1:8765 in Foxglove) or, with --mcap FILE, writes them to an MCAP file. With
--lcm-log FILE it reads a recorded LCM log (lcm-logger, `rigpose-log record --log`, the daemon's
file:// URL) instead of subscribing: the recording becomes an MCAP with the same topics. The log
is read by host_tools/common/rp_lcmlog.py (the checks of rigpose-eval's and rigpose-log's reader;
PyPI lcm's EventLog dies with SIGSEGV on a data length of 0x7fffffff): a truncated or corrupt log
is refused with one line "FILE: offset N: what", exit 1, no MCAP written; --tolerant skips the bad
stretches, one warning line each.

Topics (Foxglove's well-known schemas, host_tools/view/README.md):
  /tf                       foxglove.FrameTransform   world -> cam1 (the pose); cam1 -> camK (rig)
  /rigpose/pose             foxglove.PoseInFrame      cam1's pose in the world
  /rigpose/trajectory       foxglove.PosesInFrame     every pose so far (thinned past --max-trajectory)
  /rigpose/rig              foxglove.SceneUpdate      each rig camera as a frustum, in cam1's frame
  /rigpose/camK/image       foxglove.RawImage         mono8 image of camera K (image channel on)
  /rigpose/camK/annotations foxglove.ImageAnnotations camera K's tracked features (the daemon's
                                                      rigpose.features_t) drawn on its image
  /rigpose/pose_info        JSON  seq, flags, features used per camera, landmarks, error vs truth
  /rigpose/status           JSON  status_t: per-camera fps, features, drops; latency; filter health
Conventions are the daemon's (docs/design.md): the world is cam1's frame at the first frame
set, camera axes x right, y down, z forward, metres.
"""
import argparse
import math
import os
import signal
import sys
import time

import foxglove
from foxglove import messages as fm
from foxglove.channels import (FrameTransformChannel, ImageAnnotationsChannel,
                               PoseInFrameChannel, PosesInFrameChannel, RawImageChannel,
                               SceneUpdateChannel)
import lcm

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import rp_lcmlog  # noqa: E402  (host_tools/common/, beside this tool's folder)

try:
    from rigpose import features_t, image_t, pose_t, status_t
except ImportError:  # the build's generated package beside this tool's folder
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                    "..", "..", "build", "lcmgen", "python"))
    from rigpose import features_t, image_t, pose_t, status_t

METHODS = {pose_t.METHOD_STEREO4: "stereo4", pose_t.METHOD_STEREO2: "stereo2",
           pose_t.METHOD_GC: "gc", pose_t.METHOD_CAM1: "cam1", pose_t.METHOD_CAM2: "cam2",
           pose_t.METHOD_CAM3: "cam3", pose_t.METHOD_CAM4: "cam4", pose_t.METHOD_RC: "rc"}
FLAGS = [(pose_t.FLAG_INITIALISING, "initialising"), (pose_t.FLAG_TRACKING, "tracking"),
         (pose_t.FLAG_REINIT, "reinit"), (pose_t.FLAG_DEGRADED, "degraded"),
         (pose_t.FLAG_LOST, "lost"), (pose_t.FLAG_GATED, "gated"),
         (pose_t.FLAG_COV_RESET, "cov_reset"), (pose_t.FLAG_SCALE_WEAK, "scale_weak")]
FRUSTUM_DEPTH_M = 0.05  # drawn length of each camera's frustum


# ---- rotations (R = Rz(gamma) Ry(beta) Rx(alpha), as the daemon's configuration) ----------------
def rot_of_angles(a, b, g):
    ca, sa, cb, sb, cg, sg = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(g), \
        math.sin(g)
    return [[cg * cb, cg * sb * sa - sg * ca, cg * sb * ca + sg * sa],
            [sg * cb, sg * sb * sa + cg * ca, sg * sb * ca - cg * sa],
            [-sb, cb * sa, cb * ca]]


def quat_of_rot(r):
    """Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method)."""
    t = r[0][0] + r[1][1] + r[2][2]
    if t > 0:
        s = 2 * math.sqrt(1 + t)
        q = ((r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s, s / 4)
    elif r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = 2 * math.sqrt(1 + r[0][0] - r[1][1] - r[2][2])
        q = (s / 4, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s, (r[2][1] - r[1][2]) / s)
    elif r[1][1] > r[2][2]:
        s = 2 * math.sqrt(1 + r[1][1] - r[0][0] - r[2][2])
        q = ((r[0][1] + r[1][0]) / s, s / 4, (r[1][2] + r[2][1]) / s, (r[0][2] - r[2][0]) / s)
    else:
        s = 2 * math.sqrt(1 + r[2][2] - r[0][0] - r[1][1])
        q = ((r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, s / 4, (r[1][0] - r[0][1]) / s)
    n = math.sqrt(sum(x * x for x in q))
    return tuple(x / n for x in q)


def load_rig(path):
    """The cameras of a rigpose configuration file: name, size, intrinsics, D_k and R_k."""
    import yaml  # PyYAML (in the venv with evo)
    with open(path) as f:
        cfg = yaml.safe_load(f)
    cams = []
    for c in cfg.get("cameras", []):
        if "rotation" in c:
            v = [float(x) for x in c["rotation"]]
            r = [v[0:3], v[3:6], v[6:9]]
        else:
            r = rot_of_angles(*[float(x) for x in c.get("angles", [0, 0, 0])])
        cams.append({"name": c.get("name", "cam%d" % (len(cams) + 1)),
                     "w": int(c.get("width", 640)), "h": int(c.get("height", 480)),
                     "k": [float(x) for x in c.get("intrinsics", [800, 800, 319.5, 239.5])],
                     "D": [float(x) for x in c.get("position", [0, 0, 0])], "R": r})
    return cams


def default_rig(n):
    """Without a configuration file: n cameras drawn at cam1's place (poses only)."""
    return [{"name": "cam%d" % (i + 1), "w": 640, "h": 480, "k": [800, 800, 319.5, 239.5],
             "D": [0.0, 0.0, 0.0], "R": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]} for i in range(n)]


# ---- the viewer ---------------------------------------------------------------------------------
class View:
    def __init__(self, rig, max_traj):
        self.rig = rig
        self.max_traj = max_traj
        self.traj = []
        self.n_poses = 0
        self.n_images = 0
        self.last_seq = None
        self.features_used = {}  # camera index -> features used in the latest pose
        self.tf = FrameTransformChannel("/tf")
        self.pose = PoseInFrameChannel("/rigpose/pose")
        self.trajectory = PosesInFrameChannel("/rigpose/trajectory")
        self.scene = SceneUpdateChannel("/rigpose/rig")
        # JSON channels made now, not at their first message: advertised from the start.
        self.pose_info = foxglove.Channel("/rigpose/pose_info", message_encoding="json")
        self.status = foxglove.Channel("/rigpose/status", message_encoding="json")
        self.images = {}
        self.image_stamp = {}  # camera -> (seq, t_ns) of its latest image
        self.n_features = 0
        self.rig_logged_ns = None

    @staticmethod
    def stamp(t_ns):
        return fm.Timestamp(sec=t_ns // 1000000000, nsec=t_ns % 1000000000)

    def log_rig(self, t_ns):
        """cam1 -> camK transforms and the frusta; again every second for late clients."""
        if self.rig_logged_ns is not None and t_ns - self.rig_logged_ns < 1000000000:
            return
        self.rig_logged_ns = t_ns
        ts = self.stamp(t_ns)
        entities = []
        for k, c in enumerate(self.rig):
            if k > 0:
                qx, qy, qz, qw = quat_of_rot(c["R"])
                self.tf.log(fm.FrameTransform(
                    timestamp=ts, parent_frame_id=self.rig[0]["name"], child_frame_id=c["name"],
                    translation=fm.Vector3(x=c["D"][0], y=c["D"][1], z=c["D"][2]),
                    rotation=fm.Quaternion(x=qx, y=qy, z=qz, w=qw)), log_time=t_ns)
            fx, fy, cx, cy = c["k"]
            d = FRUSTUM_DEPTH_M
            corners = [((u - cx) / fx * d, (v - cy) / fy * d, d)
                       for u, v in ((0, 0), (c["w"], 0), (c["w"], c["h"]), (0, c["h"]))]
            # Into cam1's frame: p1 = R_k p + D_k.
            def to_rig(p, c=c, kind=fm.Point3):
                return kind(**{a: sum(c["R"][i][j] * p[j] for j in range(3)) + c["D"][i]
                               for i, a in enumerate("xyz")})
            apex = to_rig((0, 0, 0))
            pts = []
            for i in range(4):
                pts += [apex, to_rig(corners[i]), to_rig(corners[i]), to_rig(corners[(i + 1) % 4])]
            colour = fm.Color(r=1.0, g=0.55, b=0.1, a=1.0) if k == 0 else \
                fm.Color(r=0.2, g=0.7, b=1.0, a=1.0)
            entities.append(fm.SceneEntity(
                timestamp=ts, frame_id=self.rig[0]["name"], id="camera/" + c["name"],
                frame_locked=True,
                lines=[fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineList, thickness=2.0,
                                        scale_invariant=True, points=pts, color=colour)],
                texts=[fm.TextPrimitive(pose=fm.Pose(position=to_rig((0, 0, d), kind=fm.Vector3),
                                                     orientation=fm.Quaternion(w=1.0)),
                                        billboard=True, font_size=12.0, scale_invariant=True,
                                        color=colour, text=c["name"])]))
        self.scene.log(fm.SceneUpdate(entities=entities), log_time=t_ns)

    def on_pose(self, data, t_ns):
        m = pose_t.decode(data)
        self.log_rig(t_ns)
        ts = self.stamp(t_ns)
        w, x, y, z = m.quaternion
        q = fm.Quaternion(x=x, y=y, z=z, w=w)
        p = fm.Vector3(x=m.position[0], y=m.position[1], z=m.position[2])
        self.tf.log(fm.FrameTransform(timestamp=ts, parent_frame_id="world",
                                      child_frame_id=self.rig[0]["name"], translation=p,
                                      rotation=q), log_time=t_ns)
        pose = fm.Pose(position=p, orientation=q)
        self.pose.log(fm.PoseInFrame(timestamp=ts, frame_id="world", pose=pose), log_time=t_ns)
        self.traj.append(pose)
        if len(self.traj) > self.max_traj:  # keep the whole path, at half the density
            self.traj = self.traj[::2]
        self.trajectory.log(fm.PosesInFrame(timestamp=ts, frame_id="world", poses=self.traj),
                            log_time=t_ns)
        info = {"seq": m.seq, "frame": m.frame, "utime": m.utime,
                "method": METHODS.get(m.method, str(m.method)), "flags": m.flags,
                "n_gated": m.n_gated, "n_landmarks": m.n_landmarks, "est_status": m.est_status,
                "position": list(m.position), "angles": list(m.angles),
                "latency_ms": (m.publish_utime - m.utime) / 1000.0,
                "features_used": list(m.features_used[:m.n_cams]),
                "sigma_position_m": math.sqrt(max(0.0, sum(m.covariance[7 * i] for i in range(3)))),
                "sigma_rotation_rad": math.sqrt(max(0.0, sum(m.covariance[7 * i]
                                                             for i in range(3, 6))))}
        for bit, name in FLAGS:
            info["flag_" + name] = bool(m.flags & bit)
        if m.has_truth:
            info["truth"] = list(m.truth)
            info["error_position_m"] = math.sqrt(sum((m.position[i] - m.truth[i]) ** 2
                                                     for i in range(3)))
        self.pose_info.log(info, log_time=t_ns)
        self.features_used = {k: m.features_used[k] for k in range(m.n_cams)}
        self.last_seq = m.seq
        self.n_poses += 1

    def on_status(self, data, t_ns):
        m = status_t.decode(data)
        n = m.n_cams
        names = [self.rig[k]["name"] if k < len(self.rig) else "cam%d" % (k + 1) for k in range(n)]
        st = {"seq": m.seq, "last_pose_seq": m.last_pose_seq, "source": m.source,
              "hal_status": m.hal_status, "latency_ms": m.latency_ms,
              "latency_ms_max": m.latency_ms_max, "process_ms": m.process_ms,
              "set_rate_hz": m.set_rate_hz, "est_flags": m.est_flags, "n_lost": m.n_lost,
              "n_reinit": m.n_reinit, "n_cov_reset": m.n_cov_reset,
              "n_landmarks": m.n_landmarks, "pos_sigma_m": m.pos_sigma_m,
              "rot_sigma_rad": m.rot_sigma_rad,
              "cameras": {names[k]: {"state": m.cam_state[k], "fps": m.fps[k],
                                     "frames": m.frames[k], "drops": m.drops[k],
                                     "features": m.features[k],
                                     "features_used": m.features_used[k],
                                     "cam_dt_us": m.cam_dt_us[k]} for k in range(n)}}
        self.status.log(st, log_time=t_ns)

    def on_image(self, data, t_ns):
        m = image_t.decode(data)
        k = m.cam
        name = self.rig[k]["name"] if 0 <= k < len(self.rig) else "cam%d" % (k + 1)
        if k not in self.images:
            self.images[k] = (RawImageChannel("/rigpose/%s/image" % name),
                              ImageAnnotationsChannel("/rigpose/%s/annotations" % name))
        img_ch, ann_ch = self.images[k]
        ts = self.stamp(t_ns)
        img_ch.log(fm.RawImage(timestamp=ts, frame_id=name, width=m.width, height=m.height,
                               encoding="mono8", step=m.width, data=bytes(m.data)),
                   log_time=t_ns)
        self.image_stamp[k] = (m.seq, t_ns)
        self.n_images += 1

    def on_features(self, data, t_ns):
        """A camera's tracked features (rigpose.features_t, published after its image): drawn on
        that image, stamped with the image's time so Foxglove pairs them."""
        m = features_t.decode(data)
        k = m.cam
        name = self.rig[k]["name"] if 0 <= k < len(self.rig) else "cam%d" % (k + 1)
        if k not in self.images:
            self.images[k] = (RawImageChannel("/rigpose/%s/image" % name),
                              ImageAnnotationsChannel("/rigpose/%s/annotations" % name))
        seq_t = self.image_stamp.get(k)
        if seq_t is not None and seq_t[0] == m.seq:
            t_ns = seq_t[1]
        ts = self.stamp(t_ns)
        # rigpose's pixel origin is the centre of the top-left pixel, Foxglove's its corner.
        pts = [fm.Point2(x=m.u[i] + 0.5, y=m.v[i] + 0.5) for i in range(m.n)]
        used = self.features_used.get(k)
        label = "%s  set %d  %d tracked, %s used" % (name, m.seq, m.n,
                                                     "-" if used is None else used)
        self.images[k][1].log(fm.ImageAnnotations(
            points=[fm.PointsAnnotation(timestamp=ts, type=fm.PointsAnnotationType.Points,
                                        points=pts, thickness=4.0,
                                        outline_color=fm.Color(r=0.1, g=1.0, b=0.3, a=1.0),
                                        fill_color=fm.Color(r=0.1, g=1.0, b=0.3, a=1.0))],
            texts=[fm.TextAnnotation(timestamp=ts, position=fm.Point2(x=8.0, y=20.0),
                                     text=label, font_size=16.0,
                                     text_color=fm.Color(r=1.0, g=1.0, b=0.2, a=1.0),
                                     background_color=fm.Color(r=0.0, g=0.0, b=0.0, a=0.6))]),
            log_time=t_ns)
        self.n_features += m.n


def main(argv=None):
    ap = argparse.ArgumentParser(prog="rigpose-view", description=__doc__.split("\n\n")[0])
    ap.add_argument("--lcm-url", default="udpm://239.255.76.67:7667?ttl=0",
                    help="where the daemon publishes (default: this host only)")
    ap.add_argument("--pose-channel", default="RIGPOSE_POSE")
    ap.add_argument("--status-channel", default="RIGPOSE_STATUS")
    ap.add_argument("--image-channel", default="RIGPOSE_IMAGE",
                    help="rigpose.image_t channel (the daemon's lcm.image_channel); its tracked "
                         "features (rigpose.features_t) come on NAME_FEATURES")
    ap.add_argument("--config", help="the daemon's configuration file: rig cameras for the frusta")
    ap.add_argument("--port", type=int, default=8765, help="WebSocket port on 127.0.0.1")
    ap.add_argument("--mcap", metavar="FILE", help="write an MCAP file instead of serving")
    ap.add_argument("--lcm-log", metavar="FILE", help="read a recorded LCM log, not the network")
    ap.add_argument("--tolerant", action="store_true",
                    help="--lcm-log: skip truncated / corrupt stretches (warned) instead of refusing")
    ap.add_argument("--poses", type=int, default=0, help="stop after this many poses (0: never)")
    ap.add_argument("--idle", type=float, default=0.0,
                    help="stop when nothing arrived for this many seconds after the first pose")
    ap.add_argument("--max-trajectory", type=int, default=4000,
                    help="poses kept in /rigpose/trajectory before it is thinned")
    ap.add_argument("--ready", metavar="FILE", help="create FILE once subscribed (for scripts)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)

    if a.lcm_log and not a.mcap:
        ap.error("--lcm-log needs --mcap FILE")
    if a.lcm_log and not a.tolerant:  # before the MCAP is created: a corrupt log writes nothing
        try:
            rp_lcmlog.check(a.lcm_log)
        except (rp_lcmlog.LogError, OSError) as e:
            print("rigpose-view: %s" % e, file=sys.stderr)
            return 1
    foxglove.set_log_level("WARN")
    rig = load_rig(a.config) if a.config else None
    say = (lambda *x: None) if a.quiet else (lambda *x: print(*x, flush=True))

    sink = None
    if a.mcap:
        sink = foxglove.open_mcap(a.mcap, allow_overwrite=True)
    else:
        sink = foxglove.start_server(name="rigpose", host="127.0.0.1", port=a.port)
        say("rigpose-view: Foxglove WebSocket on ws://127.0.0.1:%d (open it in Foxglove)"
            % sink.port)
    view = View(rig or default_rig(1), a.max_trajectory)

    def dispatch(channel, data, t_ns):
        if channel == a.pose_channel:
            if rig is None and not view.traj:  # no configuration: as many cameras as the pose
                view.rig = default_rig(max(1, pose_t.decode(data).n_cams))
            view.on_pose(data, t_ns)
        elif channel == a.status_channel:
            view.on_status(data, t_ns)
        elif channel == a.image_channel:
            view.on_image(data, t_ns)
        elif channel == a.image_channel + "_FEATURES":
            view.on_features(data, t_ns)

    if a.lcm_log:
        try:
            for _, _, utime, channel, data in rp_lcmlog.events(a.lcm_log, a.tolerant, sys.stderr,
                                                              "rigpose-view"):
                dispatch(channel, data, utime * 1000)
                if a.poses and view.n_poses >= a.poses:
                    break
        except (rp_lcmlog.LogError, OSError) as e:  # the file changed after the check
            print("rigpose-view: %s" % e, file=sys.stderr)
            sink.close()
            return 1
    else:
        stop = [False]

        def on_signal(signum, frame):
            stop[0] = True
        signal.signal(signal.SIGINT, on_signal)
        signal.signal(signal.SIGTERM, on_signal)
        lc = lcm.LCM(a.lcm_url)
        last = [time.monotonic()]

        def handler(channel, data):
            last[0] = time.monotonic()
            dispatch(channel, data, time.time_ns())
        for ch in (a.pose_channel, a.status_channel, a.image_channel,
                   a.image_channel + "_FEATURES"):
            lc.subscribe(ch, handler)
        if a.ready:
            open(a.ready, "w").close()
        say("rigpose-view: listening on %s (%s, %s, %s)" % (a.lcm_url, a.pose_channel,
                                                          a.status_channel, a.image_channel))
        while not stop[0]:
            try:
                lc.handle_timeout(100)
            except OSError:  # interrupted by SIGINT / SIGTERM
                if stop[0]:
                    break
                raise
            if a.poses and view.n_poses >= a.poses:
                break
            if a.idle and view.n_poses and time.monotonic() - last[0] > a.idle:
                break
    if a.mcap:
        sink.close()
    else:
        time.sleep(0.5)  # let the server send what it holds before it closes the connections
        sink.stop()
    say("rigpose-view: %d poses (last seq %s), %d images, %d features%s" % (
        view.n_poses, view.last_seq, view.n_images, view.n_features,
        " -> " + a.mcap if a.mcap else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
