"""rig_subset.py IN OUT NAME... - a copy of a rigpose-render rig.yaml without the cameras NAME...

rigpose-render writes the paper's six cameras; stereo4 uses four of them (cam1, cam1b, cam3,
cam3b). The copy drops the named camera entries (each `  - name: X` block of `cameras:`), so
the replay source reads and decodes only the four images the layout uses: a 4-camera rig."""
import sys


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    drop = set(sys.argv[3:])
    out, skipping, found = [], False, set()
    for line in open(sys.argv[1]).read().splitlines(True):
        if line.startswith("  - name: "):
            name = line.split(":", 1)[1].strip()
            skipping = name in drop
            if skipping:
                found.add(name)
        elif not line.startswith("    "):
            skipping = False
        if not skipping:
            out.append(line)
    if found != drop:
        sys.exit("rig_subset: no camera %s in %s" % (", ".join(sorted(drop - found)), sys.argv[1]))
    open(sys.argv[2], "w").write("".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
