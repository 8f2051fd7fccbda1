#!/usr/bin/env python3
"""lcm_seeds.py OUT FILE.lcm... - seed inputs for the LCM message targets (fuzz_lcm_<pkg>_<type>):
for each struct of each .lcm file, three messages encoded by its lcm-gen Python binding (on
PYTHONPATH) into OUT/lcm_<pkg>_<type>/: the constructor's defaults, every field filled with small
distinct values (variable arrays of 5 elements, their size fields set), and extremes (integer
limits, NaN / inf / -0.0). The fields are read from the .lcm file itself (Debian's lcm-gen 1.3.1
writes no field types into the Python binding), so the seeds follow a changed type."""
import importlib
import math
import os
import re
import sys

LIMITS = {"int8_t": 127, "int16_t": 32767, "int32_t": 2**31 - 1, "int64_t": 2**63 - 1,
          "byte": 255}


def value(typename, i, extreme):
    if typename in LIMITS:
        return (LIMITS[typename] if i % 2 == 0 else -LIMITS[typename] - 1) if extreme else i % 100
    if typename in ("float", "double"):
        return [math.nan, math.inf, -0.0, -math.inf][i % 4] if extreme else 1.5 * i
    if typename == "boolean":
        return extreme or i % 2 == 0
    if typename == "string":
        return "x" * 40 if extreme else "s%d" % i
    return None  # nested types: left as constructed


def parse(path):
    """[(package, struct, [(typename, field, dims or None)])] of an .lcm file."""
    text = open(path).read()
    text = re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))
    pkg = re.search(r"\bpackage\s+([\w.]+)\s*;", text)
    pkg = pkg.group(1) if pkg else ""
    out = []
    for m in re.finditer(r"\bstruct\s+(\w+)\s*\{(.*?)\}", text, flags=re.S):
        fields = []
        for stmt in m.group(2).split(";"):
            stmt = stmt.strip()
            if not stmt or stmt.startswith("const"):
                continue
            f = re.match(r"([\w.]+)\s+(\w+)\s*((?:\[\s*\w+\s*\]\s*)*)$", stmt)
            if not f:
                continue
            dims = re.findall(r"\[\s*(\w+)\s*\]", f.group(3))
            dims = [int(d) if d.isdigit() else d for d in dims] or None
            fields.append((f.group(1), f.group(2), dims))
        out.append((pkg, m.group(1), fields))
    return out


def make(cls, fields, how):
    m = cls()
    if how == "defaults":
        return m
    extreme = how == "extremes"
    sizes = {}
    for k, (tn, slot, dims) in enumerate(fields):
        if dims is None:
            v = value(tn, k, extreme)
            if v is not None:
                setattr(m, slot, v)
            continue
        if len(dims) != 1:
            continue  # multi-dimensional: left as constructed
        n = dims[0]
        if isinstance(n, str):
            sizes[n] = 5
            n = 5
        if tn == "byte":
            setattr(m, slot, bytes(value("byte", k + j, extreme) & 0xff for j in range(n)))
        elif value(tn, 0, False) is not None:
            setattr(m, slot, [value(tn, k + j, extreme) for j in range(n)])
    for slot, n in sizes.items():
        setattr(m, slot, n)
    return m


def main():
    out = sys.argv[1]
    structs = [s for path in sys.argv[2:] for s in parse(path)]
    for pkg, name, fields in structs:
        cls = getattr(importlib.import_module(pkg), name)
        t = (pkg.replace(".", "_") + "_" if pkg else "") + name
        d = os.path.join(out, "lcm_" + t)
        os.makedirs(d, exist_ok=True)
        for how in ("defaults", "filled", "extremes"):
            m = make(cls, fields, how)
            if how == "defaults" and any(isinstance(getattr(m, f[1], None), str) for f in fields
                                         if f[0] == "byte"):
                setattr(m, [f[1] for f in fields if f[0] == "byte"][0], b"")  # lcm-gen's "" default
            try:
                data = m.encode()
            except Exception as e:  # a value the type cannot take: that seed is left out
                print("lcm_seeds: %s %s: %s" % (t, how, e), file=sys.stderr)
                continue
            with open(os.path.join(d, how), "wb") as f:
                f.write(data)


if __name__ == "__main__":
    main()
