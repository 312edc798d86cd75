#!/usr/bin/env python3
"""Checks the joint-aperture history of a run (its apertures.csv) against the
pattern of the seed paper's Figs. 4-6 (the demo's whole run is left out of
.ci/run's budget; see its comment):

- before grouting, a zone's centre aperture is largest late in its ungrouted
  life (second-stage cooling), not while the concrete is young and hot;
- at its grouting date most zones are open (>= 0.5 mm is the planner's rule);
- after grouting the centre stays grouted (compressed, never re-opened);
- every aperture lies in a plausible range (0 to --max-mm).

Then, as figures only (no check), where grouted layers crack open again:
per face, how much warmer than the zone's centre the face point was when
it was grouted and in which month, for the points that re-open and for
those that hold. A layer set at a face warmed by summer air goes into
tension as the face cools in winter (the seasonal face cracking that
real projects avoid by grouting in the cool season or insulating faces).
And where along its arch each re-opened centre lies: how many joints from
the nearer end of its level (the abutment), since a fixed arch's bending
under a seasonal change of temperature is largest there.

Prints the figures; exits 1 with the reason when the pattern is not met.
"""
import argparse
import collections
import csv
import datetime
import statistics
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
            (int(r["day"]), float(r["aperture_mm"]), r["state"], float(r["temperature_c"]),
             r["date"]))

failures = []
zones = late = open_at_grouting = reopened_centres = 0
lo, hi = float("inf"), float("-inf")
for (joint, zone, point), hist in rows.items():
    for _, a, s, _, _ in hist:
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


def reopening_figures():
    """The face points' warmth over their centre at grouting, re-opened
    against held, among the points grouted at least 120 days before the
    history ends (time enough to meet a winter)."""
    last = max(h[-1][0] for h in rows.values())
    months = "Jan Feb Mar Apr May Jun Jul Aug Sep Oct Nov Dec".split()
    for face in ("upstream", "downstream"):
        split = {True: [], False: []}
        for (joint, zone, point), hist in rows.items():
            grouted = next((h for h in hist if h[2] in ("grouted", "reopened")), None)
            centre = rows.get((joint, zone, "center"))
            if point != face or grouted is None or grouted[0] > last - 120 or not centre:
                continue
            t_centre = next((h[3] for h in centre if h[0] == grouted[0]), None)
            if t_centre is None:
                continue
            month = datetime.date.fromisoformat(grouted[4]).month - 1
            split[any(h[2] == "reopened" for h in hist)].append((grouted[3] - t_centre, month))
        for reopened, pts in ((True, split[True]), (False, split[False])):
            if not pts:
                continue
            warmth = sorted(p[0] for p in pts)
            n = len(warmth)
            by_month = collections.Counter(p[1] for p in pts)
            print(f"{face} points grouted by day {last - 120}, {'re-opened' if reopened else 'held'}: {n}; "
                  f"face minus centre at grouting 10/50/90 % {warmth[n // 10]:+.1f}/"
                  f"{statistics.median(warmth):+.1f}/{warmth[9 * n // 10]:+.1f} °C; grouted in "
                  + " ".join(f"{months[m]} {by_month[m]}" for m in range(12) if by_month[m]))


def reopened_centres_along_the_arch():
    """Each re-opened centre's place in its level's arch: the joints
    counted from the nearer abutment (1: the last joint before the rock)."""
    joints = collections.defaultdict(set)
    for (joint, zone, point) in rows:
        if point == "center":
            joints[zone].add(joint)
    places = collections.Counter()
    for (joint, zone, point), hist in rows.items():
        if point == "center" and any(h[2] == "reopened" for h in hist):
            level = sorted(joints[zone])
            i = level.index(joint)
            places[min(i, len(level) - 1 - i) + 1] += 1
    if places:
        print("re-opened centres by joints from the nearer abutment of their level: "
              + ", ".join(f"{k}: {places[k]}" for k in sorted(places)))


reopening_figures()
reopened_centres_along_the_arch()
for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
