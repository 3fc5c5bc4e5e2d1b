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

COLOURS = {"R": "#d62728", "G": "#2ca02c", "B": "#1f77b4"}
MIN_BATCHES = 16


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save(fig, root, out):
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(root, out + "." + ext), dpi=110 if ext == "png" else None,
                    bbox_inches="tight")
    plt.close(fig)


def profile_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    unit = p["unit"]
    r = [float(x["r_mid_" + unit]) for x in rows]
    dr = float(rows[0]["r_hi_" + unit]) - float(rows[0]["r_lo_" + unit])
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.6))
    for c in "RGB":
        v = [float(x["Rd_%s_per_%s2" % (c, unit)]) for x in rows]
        se = [float(x["Rd_%s_se_per_%s2" % (c, unit)]) for x in rows]
        lo = [a - 2 * b for a, b in zip(v, se)]
        hi = [a + 2 * b for a, b in zip(v, se)]
        n = sum(1 for x in r if x <= p["linear_range"]) or len(r)
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
    ax[0].set_title("R_d(r) near zero (linear)")
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
    fig.suptitle("%s  (bands: +-2 standard errors; %d bins of %.4g %s)" % (p["title"], len(r), dr, unit),
                 y=1.02)
    save(fig, root, p["out"])


def guide(ax, t, y, colour):
    """A 1/sqrt(t) line through the last point."""
    if not t:
        return
    t1, y1 = t[-1], y[-1]
    ts = [t[0], t1]
    ax.plot(ts, [y1 * math.sqrt(t1 / x) for x in ts], color=colour, ls=":", lw=1.0)


def convergence_plot(root, p):
    hist = read_csv(os.path.join(root, p["history"]))
    snaps = read_csv(os.path.join(root, p["snapshots"]))
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.6))
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
        ax[0].loglog(t, err, ".", ms=2.5, color=COLOURS[c], alpha=0.6,
                     label="%s |Rd(t) - Rd_ref| / Rd_ref" % c)
        ax[0].loglog(ts, rse, "-", lw=1.2, color=COLOURS[c], label="%s standard error" % c)
        guide(ax[0], ts, rse, COLOURS[c])
        ref_floor = float(h[-1]["Rd_reference_se"]) / float(h[-1]["Rd_reference"])
        ax[0].axhline(ref_floor, color=COLOURS[c], lw=0.6, ls="--")
        s = [x for x in snaps if x["channel"] == c]
        tn = [float(x["seconds"]) for x in s]
        l2 = [float(x["rRd_rel_l2_error"]) for x in s]
        ax[1].loglog(tn, l2, "o-", ms=3, lw=1.0, color=COLOURS[c], label=c)
        guide(ax[1], tn, l2, COLOURS[c])
        if s:
            ax[1].axhline(float(s[-1]["rRd_rel_l2_reference_floor"]), color=COLOURS[c], lw=0.6,
                          ls="--")
        ax[2].loglog(ts, eff, "-", lw=1.0, color=COLOURS[c], label=c)
    ax[0].set_title("total diffuse reflectance: error and standard error")
    ax[0].set_ylabel("relative error [-]")
    ax[1].set_title("profile: relative L2 error of r R_d(r)")
    ax[1].set_ylabel("relative L2 error [-]")
    ax[2].set_title("efficiency 1 / (relative variance x time), from 16 batches on")
    ax[2].set_ylabel("efficiency [1/s]")
    for a in ax:
        a.set_xlabel("wall time [s]")
        a.grid(alpha=0.3, which="both")
    ax[0].legend(fontsize=7, loc="lower left")
    ax[1].legend(fontsize=8, loc="lower left")
    ax[2].legend(fontsize=8, loc="lower right")
    fig.suptitle("%s: dotted lines 1/sqrt(t) through the last point; dashed lines: the "
                 "reference run's own noise" % p["title"], y=1.02)
    save(fig, root, p["out"])


def singular_values_plot(root, p):
    rows = read_csv(os.path.join(root, p["csv"]))
    materials = []
    for x in rows:
        if x["material"] not in materials:
            materials.append(x["material"])
    fig, ax = plt.subplots(1, len(materials), figsize=(3.6 * len(materials), 3.6), squeeze=False)
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
    fig.suptitle("Singular values of the ground-truth kernels (%s)" % p["title"], y=1.02)
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
    fig, ax = plt.subplots(1, 2, figsize=(13, 4.6))
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
    fig.suptitle(p["title"], y=1.02)
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
            if name == "linear":
                a.set_xlim(0, 0.25 * r99)
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
    fig, ax = plt.subplots(1, 2, figsize=(13, 4.6))
    engines = sorted(set(x["engine"] for x in rows))
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
            ax[1].loglog(t, [float(x["efficiency_per_s"]) for x in h], style, lw=1.2,
                         color=COLOURS[c], label="%s %s" % (e, c))
    ax[0].set_title("relative standard error of R_d against wall time")
    ax[1].set_title("efficiency 1 / (relative variance x time)")
    for a in ax:
        a.set_xlabel("wall time [s]")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.suptitle("%s: MCML (solid) and the path tracer (dashed)" % p["title"], y=1.02)
    save(fig, root, p["out"])


def main():
    with open(sys.argv[1]) as f:
        spec = json.load(f)
    root = spec["root"]
    os.makedirs(os.path.join(root, "plots"), exist_ok=True)
    for p in spec["plots"]:
        {"profile": profile_plot, "convergence": convergence_plot,
         "singular_values": singular_values_plot,
         "kernel_slices": kernel_slices_plot, "z_histogram": z_histogram_plot,
         "pencil": pencil_plot, "efficiency": efficiency_plot}[p["kind"]](root, p)


if __name__ == "__main__":
    main()
