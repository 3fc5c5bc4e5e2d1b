#!/usr/bin/env python3
"""Plots of ssslab experiment reports (matplotlib; run by `ssslab run` with Debian's python3).

Usage: plot.py SPEC.json. The spec names CSV files (relative to its "root") and what to draw;
every figure is written as PNG and SVG. Colours: the RGB channels in their own colours.
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# A title sits this far (points) above its axes: clear of a y tick label at the very top, which
# reaches half its height above the axes (the default 6 let a top label such as 6x10^5 of a
# log axis run into a long title, depending on where the data put the axis limits).
matplotlib.rcParams["axes.titlepad"] = 12.0

COLOURS = {"R": "#d62728", "G": "#2ca02c", "B": "#1f77b4"}
MIN_BATCHES = 16


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def text_boxes(fig):
    """(owner, name, bbox in pixels) of every visible text of the figure: titles, axis labels,
    tick labels, legends; owner is the index of the axes the text belongs to (-1: the figure)."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    out = []

    def add(owner, name, artist):
        if artist is not None and artist.get_visible() and \
                (not hasattr(artist, "get_text") or artist.get_text()):
            bb = artist.get_window_extent(r)
            if bb.width > 0 and bb.height > 0:
                out.append((owner, name, bb))

    if fig._suptitle is not None:
        add(-1, "suptitle", fig._suptitle)
    for leg in fig.legends:
        add(-1, "figure legend", leg)
    for i, a in enumerate(fig.axes):
        add(i, "axes %d title" % i, a.title)
        add(i, "axes %d x label" % i, a.xaxis.label)
        add(i, "axes %d y label" % i, a.yaxis.label)
        add(i, "axes %d legend" % i, a.get_legend())
        for axis, name in ((a.xaxis, "x"), (a.yaxis, "y")):
            for t in axis._update_ticks():  # the ticks drawn (inside the view)
                add(i, "axes %d %s tick %s" % (i, name, t.label1.get_text()), t.label1)
    return out


def overlaps(fig):
    """What overlaps by more than a pixel each way: two texts of the figure (an axis label over
    tick labels, crowded tick labels, a title over a neighbour's), or a text over the plotting
    area of another axes (a y label over the panel to its left). A legend inside its own axes
    is allowed."""
    boxes = text_boxes(fig)
    areas = [(i, "axes %d area" % i, a.get_window_extent()) for i, a in enumerate(fig.axes)]

    def hit(a, b):
        return min(a.x1, b.x1) - max(a.x0, b.x0) > 1 and min(a.y1, b.y1) - max(a.y0, b.y0) > 1

    found = []
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            if hit(boxes[i][2], boxes[j][2]):
                found.append("%s / %s" % (boxes[i][1], boxes[j][1]))
        for owner, name, bb in areas:
            if owner != boxes[i][0] and hit(boxes[i][2], bb):
                found.append("%s / %s" % (boxes[i][1], name))
    return found


def declutter(fig):
    """Drop the minor tick labels of an axis where its tick labels collide (a log axis spanning
    less than a decade labels its minor ticks, as 3x10^-3 4x10^-3 ...)."""
    from matplotlib.ticker import NullFormatter
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    for a in fig.axes:
        for axis in (a.xaxis, a.yaxis):
            bbs = [t.label1.get_window_extent(r) for t in axis._update_ticks()
                   if t.label1.get_visible() and t.label1.get_text()]
            if any(min(p.x1, q.x1) - max(p.x0, q.x0) > 1 and min(p.y1, q.y1) - max(p.y0, q.y0) > 1
                   for k, p in enumerate(bbs) for q in bbs[k + 1:]):
                axis.set_minor_formatter(NullFormatter())


def lift_titles(fig):
    """Move an axes' title up while it overlaps one of that axes' tick labels (where the data
    put a tick at the top edge): whatever the limits, titles stay readable."""
    r = fig.canvas.get_renderer()

    def hit(p, q):
        return min(p.x1, q.x1) - max(p.x0, q.x0) > 1 and min(p.y1, q.y1) - max(p.y0, q.y0) > 1

    for a in fig.axes:
        if not a.get_title():
            continue
        pad = matplotlib.rcParams["axes.titlepad"]
        for _ in range(6):
            fig.canvas.draw()
            tb = a.title.get_window_extent(r)
            labels = [t.label1 for axis in (a.xaxis, a.yaxis) for t in axis._update_ticks()
                      if t.label1.get_visible() and t.label1.get_text()]
            if not any(hit(tb, lab.get_window_extent(r)) for lab in labels):
                break
            pad += 6
            a.set_title(a.get_title(), pad=pad)


def save(fig, root, out, info=None):
    """PNG and SVG, and <out>.json: the caption notes the report shows under the figure, and
    facts the tests read (overlapping texts, the ranges chosen)."""
    declutter(fig)
    lift_titles(fig)
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(root, out + "." + ext), dpi=110 if ext == "png" else None,
                    bbox_inches="tight")
    info = dict(info or {})
    info.setdefault("notes", [])
    info["overlapping_texts"] = overlaps(fig)
    with open(os.path.join(root, out + ".json"), "w") as f:
        json.dump(info, f, indent=1)
    plt.close(fig)


NEAR_ZERO_FRACTION = 0.02
NEAR_ZERO_MIN_BINS = 8


def near_zero_range(r, profiles, limit):
    """The right end of the "near zero" panel: where every channel's profile has fallen to
    NEAR_ZERO_FRACTION of its peak (the first of three bins in a row below it, so that noise does
    not end it early), with a margin of a half, between NEAR_ZERO_MIN_BINS bins and `limit`.
    Profiles of dense media are a spike at r = 0 and a long flat tail on a linear scale: a range
    of a few mean free paths shows the spike as one line."""
    end = 0.0
    for v in profiles:
        peak = max(v) if v else 0
        i = 0
        while i + 2 < len(v) and not all(x < NEAR_ZERO_FRACTION * peak for x in v[i:i + 3]):
            i += 1
        end = max(end, r[min(i, len(r) - 1)])
    lo = r[min(NEAR_ZERO_MIN_BINS, len(r)) - 1]
    return min(limit, max(1.5 * end, lo))


def profile_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    unit = p["unit"]
    r = [float(x["r_mid_" + unit]) for x in rows]
    dr = float(rows[0]["r_hi_" + unit]) - float(rows[0]["r_lo_" + unit])
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.8), constrained_layout=True)
    xmax = near_zero_range(r, [[float(x["Rd_%s_per_%s2" % (c, unit)]) for x in rows]
                               for c in "RGB"], p["linear_range"])
    for c in "RGB":
        v = [float(x["Rd_%s_per_%s2" % (c, unit)]) for x in rows]
        se = [float(x["Rd_%s_se_per_%s2" % (c, unit)]) for x in rows]
        lo = [a - 2 * b for a, b in zip(v, se)]
        hi = [a + 2 * b for a, b in zip(v, se)]
        n = min(len(r), sum(1 for x in r if x <= xmax) + 1)
        ax[0].plot(r[:n], v[:n], color=COLOURS[c], lw=1.2, label=c)
        ax[0].fill_between(r[:n], lo[:n], hi[:n], color=COLOURS[c], alpha=0.25, lw=0)
        pos = [(a, b, s) for a, b, s in zip(r, v, se) if b > 0]
        ax[1].semilogy([a for a, _, _ in pos], [b for _, b, _ in pos], color=COLOURS[c], lw=1.0,
                       label=c)
        ax[1].fill_between([a for a, _, _ in pos], [max(b - 2 * s, b * 1e-3) for _, b, s in pos],
                           [b + 2 * s for _, b, s in pos], color=COLOURS[c], alpha=0.25, lw=0)
        rr = [2 * math.pi * a * b for a, b in zip(r, v)]
        rs = [2 * math.pi * a * s for a, s in zip(r, se)]
        ax[2].plot(r, rr, color=COLOURS[c], lw=1.0, label=c)
        ax[2].fill_between(r, [a - 2 * b for a, b in zip(rr, rs)], [a + 2 * b for a, b in zip(rr, rs)],
                           color=COLOURS[c], alpha=0.25, lw=0)
    ax[0].set_title("R_d(r) near zero (linear, to %g %% of the peak)" % (100 * NEAR_ZERO_FRACTION))
    ax[0].set_xlim(0, xmax)
    ax[1].set_title("R_d(r) over the whole range (log)")
    ax[2].set_title("2 pi r R_d(r): reflectance per unit radius")
    for a in ax:
        a.set_xlabel("r [%s]" % unit)
        a.grid(alpha=0.3)
        a.legend(loc="upper right")
    ax[0].set_ylabel("R_d [1/%s^2]" % unit)
    ax[1].set_ylabel("R_d [1/%s^2]" % unit)
    ax[2].set_ylabel("2 pi r R_d [1/%s]" % unit)
    ax[2].set_xscale("log")
    ax[2].set_xlim(left=max(r[0], dr / 2))
    fig.suptitle("%s  (bands: +-2 standard errors; %d bins of %.4g %s)" % (p["title"], len(r), dr,
                                                                           unit))
    save(fig, root, p["out"], {"near_zero_xlim": [0, xmax], "linear_range": p["linear_range"],
                               "near_zero_fraction": NEAR_ZERO_FRACTION})


def guide(ax, t, y, colour):
    """A 1/sqrt(t) line through the last point."""
    if not t:
        return
    t1, y1 = t[-1], y[-1]
    ts = [t[0], t1]
    ax.plot(ts, [y1 * math.sqrt(t1 / x) for x in ts], color=colour, ls=":", lw=1.0)


def log_spaced(n, k):
    """At most k indices into a series of n, evenly spaced in log(index): the markers of a
    per-batch series on a log time axis, which would otherwise pile up at the right."""
    if n <= k:
        return list(range(n))
    return sorted(set(int(round(math.exp(math.log(n) * i / (k - 1)))) - 1 for i in range(k)))


def efficiency_notes(label, t, eff, work):
    """A sentence for the caption when an efficiency 1 / (relative variance x time), flat for a
    well-behaved estimator, falls over the run: by how much, and whether the throughput (work
    per second) fell with it (the machine got slower) or not (the variance per sample rose: the
    early standard errors, from few batches, were low)."""
    if len(eff) < 8:
        return []
    q = max(2, len(eff) // 4)

    def median(v):
        v = sorted(v)
        return 0.5 * (v[(len(v) - 1) // 2] + v[len(v) // 2])

    early, late = median(eff[:q]), median(eff[-q:])
    if not (early > 0 and late < 0.75 * early):
        return []
    rate_early = median([w / x for w, x in zip(work[:q], t[:q]) if x > 0] or [0])
    rate_late = median([w / x for w, x in zip(work[-q:], t[-q:]) if x > 0] or [0])
    s = ("The efficiency of %s falls from %.3g/s to %.3g/s (%.0f %%) between %.3g s and %.3g s: "
         "its standard error shrinks more slowly than 1/sqrt(t). "
         % (label, early, late, 100 * (late / early - 1), t[0], t[-1]))
    if rate_early > 0 and rate_late < 0.85 * rate_early:
        s += ("The throughput fell with it (%.3g to %.3g per second): the runs got slower, not "
              "noisier." % (rate_early, rate_late))
    else:
        s += ("The throughput held (%.3g per second), so the variance per sample rose: the "
              "early standard errors, from few batches, were too low (rare long paths had not "
              "yet been seen)." % rate_late)
    return [s]


def convergence_plot(root, p):
    hist = read_csv(os.path.join(root, p["history"]))
    snaps = read_csv(os.path.join(root, p["snapshots"]))
    fig, ax = plt.subplots(1, 3, figsize=(14, 4.8), constrained_layout=True)
    notes, markers = [], 0
    for c in "RGB":
        h = [x for x in hist if x["channel"] == c]
        if not h:
            continue
        t = [float(x["seconds"]) for x in h]
        err = [float(x["rel_error"]) for x in h]
        # Standard errors from fewer than 16 batches are themselves too uncertain to show.
        hs = [x for x in h if int(x["batches"]) >= MIN_BATCHES]
        ts = [float(x["seconds"]) for x in hs]
        rse = [float(x["rel_se"]) for x in hs]
        eff = [float(x["efficiency_per_s"]) for x in hs]
        every = log_spaced(len(t), 40)
        markers += len(every)
        ax[0].loglog(t, err, ".", ms=4, color=COLOURS[c], alpha=0.8, markevery=every)
        ax[0].loglog(ts, rse, "-", lw=1.2, color=COLOURS[c])
        guide(ax[0], ts, rse, COLOURS[c])
        ref_floor = float(h[-1]["Rd_reference_se"]) / float(h[-1]["Rd_reference"])
        ax[0].axhline(ref_floor, color=COLOURS[c], lw=0.6, ls="--")
        s = [x for x in snaps if x["channel"] == c]
        tn = [float(x["seconds"]) for x in s]
        l2 = [float(x["rRd_rel_l2_error"]) for x in s]
        ax[1].loglog(tn, l2, "o-", ms=3, lw=1.0, color=COLOURS[c])
        guide(ax[1], tn, l2, COLOURS[c])
        if s:
            ax[1].axhline(float(s[-1]["rRd_rel_l2_reference_floor"]), color=COLOURS[c], lw=0.6,
                          ls="--")
        ax[2].loglog(ts, eff, "-", lw=1.0, color=COLOURS[c])
        notes += efficiency_notes("channel " + c, ts, eff, [float(x["photons"]) for x in hs])
    ax[0].set_title("total diffuse reflectance: error and standard error")
    ax[0].set_ylabel("relative error [-]")
    ax[1].set_title("profile: relative L2 error of r R_d(r)")
    ax[1].set_ylabel("relative L2 error [-]")
    ax[2].set_title("efficiency 1 / (rel. variance x time), 16 batches on")
    ax[2].set_ylabel("efficiency [1/s]")
    for a in ax:
        a.set_xlabel("wall time [s]")
        a.grid(alpha=0.3, which="both")
    # One legend for the figure, below the panels: the channels by colour, the curves by style.
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color=COLOURS[c], lw=2, label=c) for c in "RGB"] + [
        Line2D([], [], color="k", ls="", marker=".", ms=6, label="|R_d(t) - R_d,ref| / R_d,ref"),
        Line2D([], [], color="k", lw=1.2, label="standard error"),
        Line2D([], [], color="k", marker="o", ms=3, lw=1.0, label="profile error (snapshots)"),
        Line2D([], [], color="k", ls=":", lw=1.0, label="1/sqrt(t) through the last point"),
        Line2D([], [], color="k", ls="--", lw=0.6, label="the reference run's own noise")]
    legend_size = 10
    # matplotlib fills a legend's columns first: this order reads R G B |err| on the first row
    # and the curve styles on the second.
    handles = [handles[i] for i in (0, 4, 1, 5, 2, 6, 3, 7)]
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4,
               fontsize=legend_size, frameon=False)
    fig.suptitle(p["title"])
    save(fig, root, p["out"], {"notes": notes, "markers_per_panel": markers,
                               "legend_fontsize": legend_size})


def singular_values_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    materials = []
    for x in rows:
        if x["material"] not in materials:
            materials.append(x["material"])
    fig, ax = plt.subplots(1, len(materials), figsize=(3.6 * len(materials), 3.6), squeeze=False,
                           constrained_layout=True)
    for a, m in zip(ax[0], materials):
        for c in "RGB":
            v = [(int(x["index"]), float(x["sigma_over_sigma1"])) for x in rows
                 if x["material"] == m and x["channel"] == c]
            a.semilogy([i for i, _ in v], [s for _, s in v], "o-", ms=2.5, lw=1.0,
                       color=COLOURS[c], label=c)
        a.set_title(m)
        a.set_xlabel("index")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8)
    ax[0][0].set_ylabel("sigma_i / sigma_1")
    fig.suptitle("Singular values of the ground-truth kernels (%s)" % p["title"])
    save(fig, root, p["out"])


def kernel_slices_plot(root, p):
    rows = [x for x in read_csv(os.path.join(root, p["csv"])) if x["material"] == p["material"]]
    models = []
    for x in rows:
        if x["model"] not in models:
            models.append(x["model"])
    # Log-log, as the kernels span decades from the near-singular centre to the tail; values
    # below 1e-5 of the ground truth's peak (and negative lobes of higher-rank SVD terms) are cut.
    fig, ax = plt.subplots(2, 3, figsize=(15, 8), constrained_layout=True)
    cmap = plt.get_cmap("tab10")
    for col, c in enumerate("RGB"):
        gt_axis = [(float(x["r_mm"]), float(x["value_per_mm2"])) for x in rows
                   if x["channel"] == c and x["model"] == "ground_truth" and x["direction"] == "axis"]
        peak = max(v for _, v in gt_axis) if gt_axis else 1.0
        rmax = max([r for r, v in gt_axis if v > 1e-5 * peak] or [1.0])
        for row, direction in enumerate(("axis", "diagonal")):
            a = ax[row][col]
            for mi, model in enumerate(models):
                pts = [(float(x["r_mm"]), float(x["value_per_mm2"])) for x in rows
                       if x["channel"] == c and x["model"] == model and x["direction"] == direction]
                pts = [(r, v) for r, v in pts if r <= 1.5 * rmax and v > 0]
                style = dict(color="k", ls=":", lw=2.0) if model == "ground_truth" else \
                    dict(color=cmap(mi % 10), lw=1.0)
                a.plot([r for r, _ in pts], [v for _, v in pts], label=model, **style)
            a.set_xscale("log")
            a.set_yscale("log")
            a.set_ylim(1e-5 * peak, 3 * peak)
            a.set_title("%s, %s" % (c, direction))
            a.set_xlabel("r [mm]")
            a.grid(alpha=0.3, which="both")
    ax[0][0].set_ylabel("kernel [1/mm^2]")
    ax[1][0].set_ylabel("kernel [1/mm^2]")
    ax[0][2].legend(fontsize=7)
    fig.suptitle(p["title"])
    save(fig, root, p["out"])


def z_histogram_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    z = [float(x["z"]) for x in rows]
    fig, ax = plt.subplots(1, 2, figsize=(13, 4.6), constrained_layout=True)
    if z:
        lim = max(4.5, max(abs(v) for v in z) + 0.5)
        nb = 40
        w = 2 * lim / nb
        ax[0].hist(z, bins=nb, range=(-lim, lim), color="#777777", alpha=0.8,
                   label="%d bins" % len(z))
        xs = [-lim + 2 * lim * i / 400 for i in range(401)]
        ax[0].plot(xs, [len(z) * w * math.exp(-0.5 * x * x) / math.sqrt(2 * math.pi) for x in xs],
                   color="k", lw=1.2, label="N(0, 1)")
        mats = sorted(set(x["material"] for x in rows))
        for i, m in enumerate(mats):
            for c in "RGB":
                pts = [x for x in rows if x["material"] == m and x["channel"] == c]
                ax[1].plot([float(x["r_mid_mm"]) for x in pts], [float(x["z"]) for x in pts], ".",
                           ms=2, color=COLOURS[c], alpha=0.5)
        ax[1].set_xscale("symlog", linthresh=0.1)
        for y in (-3, 3):
            ax[1].axhline(y, color="k", lw=0.6, ls="--")
    ax[0].set_title("per-bin z-scores, all materials and channels")
    ax[0].set_xlabel("z = (volpath - MCML) / sqrt(se_v^2 + se_m^2)")
    ax[0].legend(fontsize=8)
    ax[1].set_title("z against radius (colour: channel)")
    ax[1].set_xlabel("r [mm]")
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(p["title"])
    save(fig, root, p["out"])


def pencil_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    r = [float(x["r_mid_mm"]) for x in rows]
    fig, ax = plt.subplots(3, 4, figsize=(18, 12))
    styles = ["-", "--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1)), (0, (1, 1)), (0, (8, 2))]
    model_colours = ["#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
                     "#ff7f0e", "#000000"]
    for row, c in enumerate("RGB"):
        vp = [float(x["volpath_%s_per_mm2" % c]) for x in rows]
        se = [float(x["volpath_%s_se_per_mm2" % c]) for x in rows]
        ms = [float(x["volpath_ms_%s_per_mm2" % c]) for x in rows]
        mc = [float(x["mcml_%s_per_mm2" % c]) for x in rows]
        curves = [("volpath", vp, COLOURS[c], "-", 1.6), ("volpath, >= 2 events", ms, COLOURS[c],
                                                            "--", 1.0)]
        for i, m in enumerate(p["models"]):
            key = "%s_%s_per_mm2" % (m, c)
            if rows and rows[0].get(key, "") != "":
                curves.append((m, [float(x[key]) for x in rows], model_colours[i % 8],
                               styles[i % len(styles)], 1.0))
        # The radius inside which 99 % of the tracer's reflectance leaves (trapezoid on r R dr).
        cum, tot = [], 0.0
        for i in range(len(r)):
            lo_r = float(rows[i]["r_lo_mm"])
            hi_r = float(rows[i]["r_hi_mm"])
            tot += max(vp[i], 0) * (hi_r * hi_r - lo_r * lo_r)
            cum.append(tot)
        r99 = next((float(rows[i]["r_hi_mm"]) for i in range(len(r)) if cum[i] >= 0.99 * tot),
                   r[-1] if r else 1)
        transforms = [("linear", lambda v, rr: v), ("log", lambda v, rr: v),
                      ("square root", lambda v, rr: math.sqrt(max(v, 0))),
                      ("r R_d(r)", lambda v, rr: rr * v)]
        for col, (name, f) in enumerate(transforms):
            a = ax[row][col]
            for label, v, colour, style, lw in curves:
                a.plot(r, [f(x, rr) for x, rr in zip(v, r)], color=colour, ls=style, lw=lw,
                       label=label)
            a.plot(r, [f(x, rr) for x, rr in zip(mc, r)], ".", ms=3, color="k", label="MCML")
            lo = [f(max(v - 2 * s, 0), rr) for v, s, rr in zip(vp, se, r)]
            hi = [f(v + 2 * s, rr) for v, s, rr in zip(vp, se, r)]
            a.fill_between(r, lo, hi, color=COLOURS[c], alpha=0.2, lw=0)
            if name == "log":
                a.set_yscale("log")
                pos = [v for v in vp if v > 0]
                if pos:
                    a.set_ylim(min(pos) * 0.5, max(pos) * 2)
                    # to the last bin the tracer reached (dense channels end early on the grid)
                    a.set_xlim(0, 1.05 * max(rr for rr, v in zip(r, vp) if v > 0))
            if name == "linear":  # zoomed to where the tracer's profile falls, as profile_plot
                a.set_xlim(0, near_zero_range(r, [vp], 0.25 * r99))
            elif name != "log":
                a.set_xlim(0, r99)
            a.set_title("%s, %s" % (c, name), fontsize=9)
            a.grid(alpha=0.3)
            a.set_xlabel("r [mm]")
        ax[row][0].set_ylabel("R_d [1/mm^2] per incident photon")
    ax[0][0].legend(fontsize=7)
    fig.suptitle("%s: analytic profiles against both Monte Carlo engines" % p["title"], y=1.0)
    fig.tight_layout()
    save(fig, root, p["out"])


def efficiency_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    fig, ax = plt.subplots(1, 2, figsize=(13, 4.6), constrained_layout=True)
    engines = sorted(set(x["engine"] for x in rows))
    notes = []
    for e_i, e in enumerate(engines):
        style = "-" if e_i == 0 else "--"
        for c in "RGB":
            h = [x for x in rows if x["engine"] == e and x["channel"] == c
                 and int(x["batches"]) >= MIN_BATCHES]
            if not h:
                continue
            t = [float(x["seconds"]) for x in h]
            ax[0].loglog(t, [float(x["rel_se"]) for x in h], style, lw=1.2, color=COLOURS[c],
                         label="%s %s" % (e, c))
            eff = [float(x["efficiency_per_s"]) for x in h]
            ax[1].loglog(t, eff, style, lw=1.2, color=COLOURS[c], label="%s %s" % (e, c))
            notes += efficiency_notes("%s %s" % (e, c), t, eff, [float(x["paths"]) for x in h])
    ax[0].set_title("relative standard error of R_d against wall time")
    ax[1].set_title("efficiency 1 / (relative variance x time)")
    for a in ax:
        a.set_xlabel("wall time [s]")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.suptitle("%s: MCML (solid) and the path tracer (dashed)" % p["title"])
    save(fig, root, p["out"], {"notes": notes})


def error_vs_time_plot(root, p):
    """Per scene: the RGB RMS error of every frame against the screen-space reference (left) and
    the path tracer (right, +-1 SE bars) on a log axis, against the time of p["x"] (a column:
    sss_ms, the SSS pass, or frame_ms, the whole frame) on a log axis. A line per swept model
    through its tap counts (solid: no jitter, dashed: jittered, dash-dotted: rotated axes), the
    table's models of one family (the part of the spec before ':') at the table's tap count
    joined by a dotted line, the rest as single markers."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    rows = [x for x in read_csv(os.path.join(root, p["csv"])) if x["scene"] == p["scene"]]
    xkey = p.get("x", "sss_ms")
    taps = int(p["taps"])

    def f(x, k):
        v = x.get(k, "")
        return float(v) if v not in ("", None) else 0.0

    models = []
    for x in rows:
        if x["model"] not in models:
            models.append(x["model"])
    swept = [m for m in models
             if len(set(int(x["taps"]) for x in rows if x["model"] == m)) > 1
             or any(f(x, "jitter") > 0 or f(x, "rotate") > 0 for x in rows if x["model"] == m)]
    table = [x for x in rows
             if int(x["taps"]) == taps and f(x, "jitter") == 0 and f(x, "rotate") == 0]
    families = []
    for x in table:
        fam = x["model"].split(":")[0]
        if fam not in families:
            families.append(fam)
    groups = {fam: [x for x in table if x["model"].split(":")[0] == fam] for fam in families}
    cmap = plt.get_cmap("tab10")
    series = []  # (label, rows, colour, line style, marker, annotation per row)
    for i, m in enumerate(swept):
        variants = sorted(set((f(x, "jitter"), f(x, "rotate")) for x in rows if x["model"] == m))
        for j, rot in variants:
            pts = sorted([x for x in rows if x["model"] == m and f(x, "jitter") == j
                          and f(x, "rotate") == rot], key=lambda x: int(x["taps"]))
            name = m + (", jitter %g" % j if j > 0 else "") + (", rotated" if rot > 0 else "")
            style = "-." if rot > 0 else ("--" if j > 0 else "-")
            series.append((name, pts, cmap(i % 10), style, "o", [x["taps"] for x in pts],
                           (3, -9) if j > 0 else ((3, 9) if rot > 0 else (3, 3))))
    k = len(swept)
    for fam in families:
        g = groups[fam]
        if len(g) >= 2:
            params = [x["model"].split(":", 1)[1] if ":" in x["model"] else x["model"] for x in g]
            # "rank=2", "n=3": the parameter beside its point (a value alone would read as taps)
            short = [q if len(q) <= 8 else q.split("=", 1)[-1] for q in params]
            last = params[-1].split("=", 1)[-1]
            series.append(("%s:%s .. %s (%d taps)" % (fam, params[0], last, taps), g,
                           cmap(k % 10), ":", "s", short, (-4, 5)))
            k += 1
        elif g[0]["model"] not in swept:
            series.append((g[0]["model"], g, cmap(k % 10), "none", "D", [""], (0, 0)))
            k += 1

    fig, ax = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    notes = []
    panels = [("rms_vs_reference_rgb", "against the screen-space 2D reference (separability)"),
              ("rms_vs_volpath_rgb", "against the path tracer (noise-corrected, +-1 SE)")]
    handles = {}  # label -> what drew it first (a series may be drawn in one panel only)
    for a, (key, title) in zip(ax, panels):
        ys = []
        dropped = 0
        for label, pts, colour, ls, marker, ann, offset in series:
            keep = [(x, t) for x, t in zip(pts, ann) if f(x, key) > 0 and f(x, xkey) > 0]
            dropped += len(pts) - len(keep)
            if not keep:
                continue
            xv = [f(x, xkey) for x, _ in keep]
            yv = [f(x, key) for x, _ in keep]
            se = [f(x, key + "_se") for x, _ in keep]
            ys += yv
            # On a log axis a bar reaching zero runs off the bottom (the limits follow the points).
            lo = [min(s, 0.999 * y) for s, y in zip(se, yv)]
            bars = a.errorbar(xv, yv, yerr=[lo, se] if any(se) else None, color=colour, ls=ls,
                              marker=marker, ms=4, lw=1.2, capsize=2, elinewidth=0.7,
                              label=label)
            for b in bars[1] + bars[2]:  # caps and bars fainter than the points and lines
                b.set_alpha(0.35)
            handles.setdefault(label, bars)
            for xx, yy, (_, t) in zip(xv, yv, keep):
                if t:
                    a.annotate(t, (xx, yy), xytext=offset, textcoords="offset points",
                               fontsize=6, color=colour)
        a.set_yscale("log")
        a.set_xscale("log")
        # Times as plain numbers at 1, 2 and 5 times the powers of ten (a pass's times span a
        # decade or two: the default labels only the powers).
        a.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        a.xaxis.set_major_formatter(FuncFormatter(lambda v, _: "%g" % v))
        a.xaxis.set_minor_formatter(NullFormatter())
        if ys:
            a.set_ylim(min(ys) / 2, max(ys) * 2)
        a.set_title(title)
        a.set_xlabel("frame time [ms]" if xkey == "frame_ms" else "SSS pass time [ms]")
        a.grid(alpha=0.3, which="both")
        if dropped:
            notes.append("%d of its frames score zero %s (not drawn on the log axes)." %
                         (dropped, "against the path tracer: within its noise"
                          if key == "rms_vs_volpath_rgb" else "against the reference"))
    ax[0].set_ylabel("RMS error (RGB), radiance")
    order = [q[0] for q in series if q[0] in handles]
    if order:
        ax[1].legend([handles[q] for q in order], order, fontsize=7, loc="best")
    frames = [x for x in rows if f(x, "frame_ms") > 0]
    if frames:
        rest = [f(x, "frame_ms") - f(x, "sss_ms") for x in frames]
        share = [f(x, "sss_ms") / f(x, "frame_ms") for x in frames]
        notes.append("The rest of these frames (raster, shadow maps and lighting, the same for "
                     "every model, and the composite) took %.4g to %.4g ms: the SSS pass is "
                     "%.2g to %.2g %% of the frame time." %
                     (min(rest), max(rest), 100 * min(share), 100 * max(share)))
    fig.suptitle("%s: error against %s" %
                 (p["scene"], "frame time" if xkey == "frame_ms" else "SSS pass time"))
    save(fig, root, p["out"], {"notes": notes, "x": xkey, "series": [q[0] for q in series]})


def sweep_plot(root, p):
    """Panels of one table's rows of p["scene"]: p["y"] (+-1 SE from the column y + "_se")
    against each panel's "x" column. A panel draws a line per combination of its "series"
    columns (the variant's other parameters), in order of x; "min_points" leaves out series with
    fewer points (single variants); "xscale" linear, log or symlog (for a sweep that includes 0);
    "markers_only" draws points without lines (an error against time cloud). Rows whose y is 0
    (within the path tracer's noise) cannot sit on the log y axis and are counted in a note."""
    rows = [x for x in read_csv(os.path.join(root, p["csv"])) if x["scene"] == p["scene"]]
    ykey = p["y"]

    def f(x, k):
        v = x.get(k, "")
        return float(v) if v not in ("", None) else 0.0

    panels = p["panels"]
    fig, ax = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 4.4),
                           constrained_layout=True, squeeze=False)
    cmap = plt.get_cmap("tab10")
    notes = []
    drawn = []
    for a, q in zip(ax[0], panels):
        xkey = q["x"]
        groups = {}
        for x in rows:
            key = ", ".join("%s %s" % (c, x[c]) for c in q.get("series", []))
            groups.setdefault(key, []).append(x)
        dropped, k, ys = 0, 0, []
        for label, g in groups.items():
            if len(g) < q.get("min_points", 1):
                continue
            g = sorted(g, key=lambda x: f(x, xkey))
            keep = [x for x in g if f(x, ykey) > 0]
            dropped += len(g) - len(keep)
            if not keep:
                continue
            yv = [f(x, ykey) for x in keep]
            se = [f(x, ykey + "_se") for x in keep]
            lo = [min(e, 0.999 * y) for e, y in zip(se, yv)]
            bars = a.errorbar([f(x, xkey) for x in keep], yv, yerr=[lo, se],
                              color=cmap(k % 10), ls="none" if q.get("markers_only") else "-",
                              marker="os^Dv<>ph*"[k % 10], ms=4, lw=1.2, capsize=2,
                              elinewidth=0.7, label=label or ykey)
            for b in bars[1] + bars[2]:
                b.set_alpha(0.35)
            ys += yv
            k += 1
        drawn.append(k)
        a.set_yscale("log")
        xs = q.get("xscale", "linear")
        if xs == "symlog":
            a.set_xscale("symlog", linthresh=q.get("linthresh", 1e-3))
        else:
            a.set_xscale(xs)
        if ys:
            a.set_ylim(min(ys) / 2, max(ys) * 2)
        a.set_xlabel(q.get("xlabel", xkey))
        a.set_title(q.get("title", ""), fontsize=10)
        a.grid(alpha=0.3, which="both")
        if k:
            a.legend(fontsize=6, loc="best")
        if dropped:
            notes.append("%s: %d of its variants score zero (within the path tracer's noise; not "
                         "drawn on the log axis)." % (q.get("title", xkey), dropped))
    ax[0][0].set_ylabel(p.get("ylabel", ykey))
    fig.suptitle(p.get("title", p["scene"]))
    save(fig, root, p["out"], {"notes": notes, "series_per_panel": drawn})


def main():
    with open(sys.argv[1]) as f:
        spec = json.load(f)
    root = spec["root"]
    os.makedirs(os.path.join(root, "plots"), exist_ok=True)
    for p in spec["plots"]:
        {"profile": profile_plot, "convergence": convergence_plot,
         "singular_values": singular_values_plot,
         "kernel_slices": kernel_slices_plot, "z_histogram": z_histogram_plot,
         "pencil": pencil_plot, "efficiency": efficiency_plot,
         "error_vs_time": error_vs_time_plot, "sweep": sweep_plot}[p["kind"]](root, p)


if __name__ == "__main__":
    main()
