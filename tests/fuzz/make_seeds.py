#!/usr/bin/env python3
"""make_seeds.py - writes the committed seed corpora tests/fuzz/seed/<target>/ and the configuration
dictionary tests/fuzz/config.dict. Run by hand when a format changes (the outputs are committed,
small: a few KB per target), from the repository's root, with the build's Python bindings:

    PYTHONPATH=build/lcmgen/python .venv/bin/python tests/fuzz/make_seeds.py

Needs Pillow (PIL, which evo brings into .venv) for the PNG and JPEG seeds, and the lcm package.
The LCM message seeds are made by lcm_seeds.py (also run at build time into build/fuzz/gen/)."""
import io
import os
import re
import shutil
import struct
import subprocess
import sys

from PIL import Image
import lcm

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SEED = os.path.join(ROOT, "tests", "fuzz", "seed")


def put(target, name, data):
    d = os.path.join(SEED, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def config():
    for src, name in (("config/sim.yaml", "sim.yaml"), ("tests/vm/vivid_rig.yaml", "v4l2.yaml"),
                      ("host_tools/research/realdata/profiles/kitti00.yaml", "replay.yaml")):
        put("config", name, open(os.path.join(ROOT, src), "rb").read())
    put("config", "minimal_replay.yaml", """version: 1
source: {kind: replay, replay_index: frames.csv}
cameras:
  - {name: c0, device: cam0, width: 64, height: 48, intrinsics: [50, 50, 32, 24],
     distortion: [0, 0, 0, 0, 0], position: [0, 0, 0], rotation: [1, 0, 0, 0, 1, 0, 0, 0, 1]}
estimator: {method: cam1}
""")
    put("config", "bad_anchor.yaml", "version: 1\nsource: &s {kind: sim}\nlcm: *s\n")
    # the dictionary: every key and word of the schema
    words = set(re.findall(r"`([a-z_][a-z_0-9]*)`", open(os.path.join(ROOT, "config/README.md")).read()))
    words |= set(re.findall(r"^\s*-?\s*([a-z_][a-z_0-9]*):", open(os.path.join(ROOT, "config/sim.yaml")).read(), re.M))
    with open(os.path.join(ROOT, "tests", "fuzz", "config.dict"), "w") as f:
        f.write("# libFuzzer dictionary of fuzz_config: the schema's keys and words (make_seeds.py)\n")
        for w in sorted(words):
            f.write('"%s"\n"%s:"\n' % (w, w))
        for tok in ("---", "...", "- ", "[", "]", "{", "}", ": ", "&a", "*a", "!!str", "|", ">",
                    "1e-300", "1e300", "-1", "nan", ".inf", "true", "0x7fffffff", "~", "null"):
            f.write('"%s"\n' % tok.replace("\\", "\\\\").replace('"', '\\"'))


def replay_index():
    put("replay_index", "one_cam", "utime_us,cam0\n1000,a.pgm\n2000,b.png\n3000,a.pgm\n")
    put("replay_index", "two_cams_truth",
        "utime_us,cam0,cam1\n# a comment\n\n1000,a.pgm,b.png\n2000, b.png , a.pgm\n"
        "\0utime_us,tx,ty,tz,alpha,beta,gamma\n1000,0,0,0,0,0,0\n2000,0.1,0,0,0,0,0.01\n")
    put("replay_index", "errors",
        "utime_us,cam0,cam1\n1000,a.pgm,missing.png\n999,a.pgm,b.png\nx,a.pgm,b.png\n"
        "3000,a.pgm\n4000,.,..\n5000,a.pgm,b.png,c\n9223372036854775807,a.pgm,b.png\n")
    put("replay_index", "crlf_named", "utime_us,cam1,cam0\r\n10,b.png,a.pgm\r\n20,a.pgm,b.png\r\n")
    put("replay_index", "paced", "#rt paced at 1 ms\nutime_us,cam0,cam1\n1000,a.pgm,b.png\n"
        "1500,b.png,a.pgm\n2000,a.pgm,a.pgm\n")
    # per-camera capture times (utime_us_<column>), one of them malformed, one too far
    put("replay_index", "camera_times",
        "utime_us,cam0,utime_us_cam1,cam1,utime_us_cam0\n1000,a.pgm,1012,b.png,990\n"
        "2000,b.png,1975,a.pgm,2040\n3000,a.pgm,x,b.png,3000\n"
        "4000,a.pgm,2147487648,b.png,4000\n5000,a.pgm,-5000,b.png,5001\n")


def image():
    px = bytes((i * 5) % 256 for i in range(48))
    put("image", "grey.pgm", b"P5\n8 6\n255\n" + px)
    put("image", "comments.pgm", b"P5 # w\n8\t6 # h\n# max\n100\n" + bytes(b % 101 for b in px))
    im = Image.frombytes("L", (8, 6), px)
    def png(img, **kw):
        b = io.BytesIO()
        img.save(b, "PNG", **kw)
        return b.getvalue()
    put("image", "grey.png", png(im))
    put("image", "rgb.png", png(im.convert("RGB")))
    put("image", "palette.png", png(im.convert("P")))
    put("image", "rgba.png", png(im.convert("RGBA")))
    put("image", "grey16.png", png(Image.frombytes("I;16", (8, 6), bytes(96))))
    put("image", "grey_alpha.png", png(im.convert("LA")))
    put("image", "big_blank.png", png(Image.new("L", (640, 480))))


def mjpeg():
    grad = bytes((x * 8 + y * 4) % 256 for y in range(16) for x in range(32))
    im = Image.frombytes("L", (32, 16), grad)
    def jpg(img, **kw):
        b = io.BytesIO()
        img.save(b, "JPEG", **kw)
        return struct.pack(">HH", img.width, img.height) + b.getvalue()
    put("mjpeg", "grey_32x16.jpg", jpg(im, quality=75))
    put("mjpeg", "ycc420_32x16.jpg", jpg(im.convert("RGB"), quality=50, subsampling=2))
    put("mjpeg", "ycc422_32x16.jpg", jpg(im.convert("RGB"), quality=90, subsampling=1))
    put("mjpeg", "progressive_32x16.jpg", jpg(im.convert("RGB"), progressive=True))
    put("mjpeg", "optimized_24x24.jpg", jpg(Image.new("RGB", (24, 24), (200, 10, 10)), optimize=True))
    put("mjpeg", "wrong_size.jpg", struct.pack(">HH", 16, 16) + jpg(im)[4:])


def lcmlog():
    sys.path.insert(0, os.path.join(ROOT, "build", "lcmgen", "python"))
    from rigpose import pose_t, image_t
    tmp = os.path.join(SEED, ".tmp.log")
    log = lcm.EventLog(tmp, "w", overwrite=True)
    for i in range(3):
        p = pose_t()
        p.utime, p.seq = 1000 * i, i
        p.quaternion = [1.0, 0.0, 0.0, 0.0]
        log.write_event(p.utime, "RIGPOSE_POSE", p.encode())
        m = image_t()
        m.utime, m.seq, m.width, m.height, m.size = 1000 * i, i, 4, 2, 8
        m.data = bytes(range(8))
        log.write_event(p.utime, "RIGPOSE_IMAGE", m.encode())
    log.close()
    raw = open(tmp, "rb").read()
    os.unlink(tmp)
    put("lcmlog", "six_events.log", raw)
    put("lcmlog", "truncated.log", raw[:-17])
    first = 28 + struct.unpack(">ii", raw[20:28])[0] + struct.unpack(">ii", raw[20:28])[1]
    put("lcmlog", "garbage.log", raw[:first] + b"\x00garbage\xed\xa1\xda\x01" + bytes(30) + raw[first:])
    b = bytearray(raw)
    b[24:28] = struct.pack(">I", 0x7fffffff)
    put("lcmlog", "huge_length.log", bytes(b))


def lcm_types():
    gen = os.path.join(SEED, ".gen")
    lcms = sorted(os.path.join(ROOT, "lcm_types", f) for f in os.listdir(os.path.join(ROOT, "lcm_types"))
                  if f.endswith(".lcm"))
    subprocess.check_call([sys.executable, os.path.join(ROOT, "tests", "fuzz", "lcm_seeds.py"), gen] + lcms)
    for t in os.listdir(gen):
        shutil.rmtree(os.path.join(SEED, t), ignore_errors=True)
        shutil.copytree(os.path.join(gen, t), os.path.join(SEED, t))
    shutil.rmtree(gen)


if __name__ == "__main__":
    for f in (config, replay_index, image, mjpeg, lcmlog, lcm_types):
        f()
