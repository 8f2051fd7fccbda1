"""Merge the benchmark sections (one flat JSON object each) into one file.

usage: merge_json.py OUT PART.json...

A figure named in two sections is an error (two benchmarks claiming one name).
"""
import json
import sys


def main(argv):
    if len(argv) < 2:
        print("usage: merge_json.py OUT PART.json...", file=sys.stderr)
        return 2
    out, parts = argv[0], argv[1:]
    merged, owner = {}, {}
    for path in parts:
        try:
            with open(path) as f:
                data = json.load(f)
        except (OSError, ValueError) as e:
            print(f"merge_json: {path}: {e}", file=sys.stderr)
            return 1
        if not isinstance(data, dict):
            print(f"merge_json: {path}: not a JSON object", file=sys.stderr)
            return 1
        for k, v in data.items():
            if k in merged:
                print(f"merge_json: figure '{k}' in both {owner[k]} and {path}", file=sys.stderr)
                return 1
            merged[k], owner[k] = v, path
    with open(out, "w") as f:
        json.dump(merged, f, indent=2, sort_keys=True)
        f.write("\n")
    print(f"bench: {len(merged)} figures from {len(parts)} sections -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
