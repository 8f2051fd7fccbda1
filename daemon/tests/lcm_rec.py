#!/usr/bin/env python3
"""Records LCM channels into an LCM log file for the tests (PyPI `lcm`): subscribes to every
channel matching --channels on --url, touches --ready once subscribed, writes each message as it
comes, and stops on SIGTERM / SIGINT or after --timeout seconds (exit 0; 2 on timeout)."""
import argparse
import os
import signal
import sys
import time

import lcm


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--url", required=True)
    ap.add_argument("--channels", required=True, help="LCM channel regex")
    ap.add_argument("--out", required=True)
    ap.add_argument("--ready", required=True)
    ap.add_argument("--timeout", type=float, default=120.0)
    a = ap.parse_args()
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    lc = lcm.LCM(a.url)
    log = lcm.EventLog(a.out, "w", overwrite=True)
    lc.subscribe(a.channels, lambda ch, data: log.write_event(int(time.time() * 1e6), ch, data))
    open(a.ready, "w").close()
    t_end = time.monotonic() + a.timeout
    while not stop and time.monotonic() < t_end:
        try:
            lc.handle_timeout(50)
        except OSError:  # interrupted by the signal that stops it (raised before its handler ran)
            stop.append(1)
    log.close()
    return 0 if stop else 2


if __name__ == "__main__":
    sys.exit(main())
