#!/usr/bin/env python3
"""make_wheel.py PKGDIR VERSION OUTDIR - packs the lcm-gen Python package `rigpose` (PKGDIR/rigpose)
into a pure-Python wheel OUTDIR/rigpose_lcm-VERSION-py3-none-any.whl, so subscribers install the
types with `pip install build/lcmgen/rigpose_lcm-*.whl` instead of setting PYTHONPATH.

Written here rather than by a build backend: a wheel is a zip with three metadata files, and
this way the build needs no package from the network. Requires-Dist names PyPI `lcm`, the
runtime the generated code imports.
"""
import base64
import hashlib
import os
import sys
import zipfile

NAME = "rigpose_lcm"


def digest(data):
    h = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return "sha256=" + h


def main():
    pkgdir, version, outdir = sys.argv[1:4]
    src = os.path.join(pkgdir, "rigpose")
    files = sorted(f for f in os.listdir(src) if f.endswith(".py"))
    if "__init__.py" not in files:
        sys.exit("make_wheel: %s has no __init__.py" % src)
    info = "%s-%s.dist-info" % (NAME, version)
    meta = {
        "METADATA": "Metadata-Version: 2.1\nName: rigpose-lcm\nVersion: %s\n"
                    "Summary: LCM message types of the rigpose pose daemon (lcm-gen)\n"
                    "Requires-Dist: lcm\n" % version,
        "WHEEL": "Wheel-Version: 1.0\nGenerator: rigpose make_wheel.py\n"
                 "Root-Is-Purelib: true\nTag: py3-none-any\n",
        "top_level.txt": "rigpose\n",
    }
    out = os.path.join(outdir, "%s-%s-py3-none-any.whl" % (NAME, version))
    record = []
    with zipfile.ZipFile(out + ".tmp", "w", zipfile.ZIP_DEFLATED) as z:
        for f in files:
            data = open(os.path.join(src, f), "rb").read()
            arc = "rigpose/" + f
            z.writestr(arc, data)
            record.append("%s,%s,%d" % (arc, digest(data), len(data)))
        for f, text in meta.items():
            data = text.encode()
            z.writestr(info + "/" + f, data)
            record.append("%s/%s,%s,%d" % (info, f, digest(data), len(data)))
        record.append("%s/RECORD,," % info)
        z.writestr(info + "/RECORD", "\n".join(record) + "\n")
    os.replace(out + ".tmp", out)
    print("make_wheel: %s (%d modules)" % (out, len(files)))


if __name__ == "__main__":
    main()
