#!/usr/bin/env python3
"""Checks the joint-aperture history of a demo run against the pattern of the
seed paper's Figs. 4-6 (run by .ci/run on the demo's apertures.csv):

- before grouting, a zone's centre aperture is largest late in its ungrouted
  life (second-stage cooling), not while the concrete is young and hot;
- at its grouting date most zones are open (>= 0.5 mm is the planner's rule);
- after grouting the centre stays grouted (compressed, never re-opened);
- every aperture lies in a plausible range (0 to --max-mm).

Prints the figures; exits 1 with the reason when the pattern is not met.
"""
import argparse
import collections
import csv
import sys

ap = argparse.ArgumentParser()
ap.add_argument("csv")
ap.add_argument("--max-mm", type=float, default=4.0)
ap.add_argument("--late-fraction", type=float, default=0.6)
args = ap.parse_args()

rows = collections.defaultdict(list)
with open(args.csv) as f:
    for r in csv.DictReader(f):
        rows[(int(r["joint"]), int(r["zone"]), r["point"])].append(
            (int(r["day"]), float(r["aperture_mm"]), r["state"]))

failures = []
zones = late = open_at_grouting = reopened_centres = 0
lo, hi = float("inf"), float("-inf")
for (joint, zone, point), hist in rows.items():
    for _, a, s in hist:
        if s not in ("grouted", "reopened"):
            lo, hi = min(lo, a), max(hi, a)
    if point != "center":
        continue
    zones += 1
    pre = [h for h in hist if h[2] not in ("grouted", "reopened")]
    post = [h for h in hist if h[2] in ("grouted", "reopened")]
    if not pre or not post:
        failures.append(f"joint {joint} zone {zone}: not grouted within the run")
        continue
    start, end = pre[0][0], pre[-1][0]
    peak = max(pre, key=lambda h: h[1])
    if peak[0] >= start + args.late_fraction * (end - start):
        late += 1
    if pre[-1][1] >= 0.5:
        open_at_grouting += 1
    if any(h[2] == "reopened" for h in post):
        reopened_centres += 1

print(f"{zones} zones: centre aperture peaks in the last {100 * (1 - args.late_fraction):.0f}% "
      f"of the ungrouted period in {late}; >= 0.5 mm at grouting in {open_at_grouting}; "
      f"re-opened centres {reopened_centres}; ungrouted apertures in [{lo:.3f}, {hi:.3f}] mm")
if zones == 0:
    failures.append("no zones")
if late < 0.9 * zones:
    failures.append(f"only {late}/{zones} zones open most at the end of cooling")
if open_at_grouting < 0.5 * zones:
    failures.append(f"only {open_at_grouting}/{zones} zones open >= 0.5 mm at grouting")
if reopened_centres:
    failures.append(f"{reopened_centres} zone centres re-opened after grouting")
if lo < -1e-3 or hi > args.max_mm:
    failures.append(f"apertures outside [0, {args.max_mm}] mm")
for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
