#include "experiments/runner/engines.h"

#include "approx/diffusion.h"
#include "core/format.h"
#include "core/stats.h"
#include "experiments/runner/report.h"
#include "volpath/pencil.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

namespace ssslab::runner {

namespace {

// ---- display bins: the engines' bins merged into at most ~160 annuli --------------------------

struct Bins {
    std::vector<int> first;  // first original bin of each display bin; back() = nr
    double dr = 0;
    size_t size() const { return first.size() - 1; }
    double lo(size_t i) const { return first[i] * dr; }
    double hi(size_t i) const { return first[i + 1] * dr; }
};

// The first 20 bins as they are, then groups of 2, 4, 8, ... bins, 20 groups of each size.
Bins display_bins(int nr, double dr) {
    Bins b;
    b.dr = dr;
    int at = 0, width = 1, count = 0;
    while (at < nr) {
        b.first.push_back(at);
        at = std::min(nr, at + width);
        if (++count == 20) {
            count = 0;
            width *= 2;
        }
    }
    b.first.push_back(nr);
    return b;
}

// Area-weighted mean over display bins of a profile channel, and its standard error (bins are
// summed in quadrature: an upper bound, since a path leaves through one bin only).
void merge(const RadialProfile& p, int c, const Bins& b, std::vector<double>& v,
           std::vector<double>& se) {
    v.assign(b.size(), 0.0);
    se.assign(b.size(), 0.0);
    for (size_t k = 0; k < b.size(); ++k) {
        double w = 0, a = 0, e = 0;
        for (int i = b.first[k]; i < b.first[k + 1]; ++i) {
            const double area = (2.0 * i + 1.0);  // ring area / (pi dr^2)
            w += p.rd_per_cm2[c][static_cast<size_t>(i)] * area;
            e += std::pow(p.se_per_cm2[c][static_cast<size_t>(i)] * area, 2);
            a += area;
        }
        v[k] = w / a;
        se[k] = std::sqrt(e) / a;
    }
}

// Relative L2 distance of r R(r) over the display bins (weighted_rel_l2 with a_k = dr_k r_k^2,
// r_k the bin's mid radius), with the standard error the reference's noise gives it. (The bins
// of one run are slightly correlated, which this neglects.)
RelL2 rel_l2_rr(const Bins& b, const std::vector<double>& m, const std::vector<double>& ref,
                const std::vector<double>& ref_se = {}) {
    std::vector<double> a(b.size());
    for (size_t k = 0; k < b.size(); ++k) {
        const double mid = 0.5 * (b.lo(k) + b.hi(k));
        a[k] = (b.hi(k) - b.lo(k)) * mid * mid;
    }
    return weighted_rel_l2(a, m, ref, ref_se);
}

// What every model is compared with, per material and channel.
struct Reference {
    std::vector<double> all, all_se, ms, ms_se, mcml, mcml_se;
    double rd = 0, rd_se = 0, rd_ms = 0, rd_ms_se = 0, rsp = 0;
};

struct ModelCurve {
    std::string name;
    bool single = false, fresnel = false;
    std::vector<double> v;  // adjusted like for like (x (1 - Rsp) where needed)
    double rd = 0;          // adjusted total
    std::string error;      // why the model could not be evaluated (empty if it was)
};

struct MaterialPencil {
    Bins bins;
    std::array<Reference, 3> ref;
    std::array<std::vector<ModelCurve>, 3> models;
};

MaterialPencil pencil_data(const ExperimentRun& r, const MaterialEntry& me, bool with_models) {
    MaterialPencil out;
    const RadialProfile all = volpath_profile(r, me.label, false);
    const RadialProfile single = volpath_profile(r, me.label, true);
    const RadialProfile mc = material_profile(r, me.label);
    out.bins = display_bins(all.nr, all.dr_cm);
    for (int c = 0; c < 3; ++c) {
        Reference& f = out.ref[static_cast<size_t>(c)];
        std::vector<double> ss, ss_se;
        merge(all, c, out.bins, f.all, f.all_se);
        merge(single, c, out.bins, ss, ss_se);
        merge(mc, c, out.bins, f.mcml, f.mcml_se);
        f.ms.resize(f.all.size());
        // The multiple-scattering part's SE: the total's (Var(ms) = Var(all) - Var(ss) plus a
        // term of order mean(ms) mean(ss) / N; the total's is the larger of the two in practice).
        f.ms_se = f.all_se;
        for (size_t k = 0; k < f.all.size(); ++k) f.ms[k] = f.all[k] - ss[k];
        f.rd = all.rd_total[c];
        f.rd_se = all.rd_total_se[c];
        f.rd_ms = all.rd_total[c] - single.rd_total[c];
        f.rd_ms_se = all.rd_total_se[c];
        f.rsp = all.rsp[c];
        if (!with_models) continue;
        for (const std::string& name : r.exp.pencil.models.names()) {
            ModelCurve m;
            m.name = name;
            try {
                const approx::DiffusionMedium dm = approx::diffusion_medium(me.medium, c);
                const auto model = r.exp.pencil.models.make(name, dm, c);
                m.single = model->includes_single_scattering();
                m.fresnel = model->includes_entry_fresnel();
                const double scale = m.fresnel ? 1.0 : 1.0 - f.rsp;
                m.v.resize(out.bins.size());
                for (size_t k = 0; k < out.bins.size(); ++k)
                    m.v[k] = scale * model->annulus_mean(out.bins.lo(k), out.bins.hi(k));
                m.rd = scale * model->total_rd();
            } catch (const std::exception& e) {
                m.error = e.what();
            }
            out.models[static_cast<size_t>(c)].push_back(std::move(m));
        }
    }
    return out;
}

std::string pencil_csv(const MaterialPencil& p, const std::vector<std::string>& models) {
    std::ostringstream os;
    os << "r_lo_mm,r_hi_mm,r_mid_mm";
    for (int c = 0; c < 3; ++c) {
        const std::string ch = kChannelNames[c];
        os << ",mcml_" << ch << "_per_mm2,mcml_" << ch << "_se_per_mm2,volpath_" << ch
           << "_per_mm2,volpath_" << ch << "_se_per_mm2,volpath_ms_" << ch << "_per_mm2";
        for (const auto& m : models) os << "," << m << "_" << ch << "_per_mm2";
    }
    os << "\n";
    const double mm = 10.0, per_mm2 = 0.01;
    for (size_t k = 0; k < p.bins.size(); ++k) {
        os << format_g(p.bins.lo(k) * mm, 10) << ',' << format_g(p.bins.hi(k) * mm, 10) << ','
           << format_g(0.5 * (p.bins.lo(k) + p.bins.hi(k)) * mm, 10);
        for (int c = 0; c < 3; ++c) {
            const Reference& f = p.ref[static_cast<size_t>(c)];
            os << ',' << format_g(f.mcml[k] * per_mm2, 10) << ','
               << format_g(f.mcml_se[k] * per_mm2, 10) << ',' << format_g(f.all[k] * per_mm2, 10)
               << ',' << format_g(f.all_se[k] * per_mm2, 10) << ','
               << format_g(f.ms[k] * per_mm2, 10);
            for (const auto& m : p.models[static_cast<size_t>(c)])
                os << ',' << (m.error.empty() ? format_g(m.v[k] * per_mm2, 10) : "");
        }
        os << "\n";
    }
    return os.str();
}

struct CrossRow {
    int bins = 0;
    double chi2 = 0, p = 1, max_abs_z = 0, rd_z = 0;
    std::vector<std::pair<double, double>> z;  // (r_mid_mm, z)
};

CrossRow crossval(const RadialProfile& a, const RadialProfile& b, int c, double max_rel_se) {
    CrossRow out;
    for (size_t i = 0; i < a.rd_per_cm2[c].size(); ++i) {
        const double va = a.rd_per_cm2[c][i], vb = b.rd_per_cm2[c][i];
        const double sa = a.se_per_cm2[c][i], sb = b.se_per_cm2[c][i];
        if (!(sa > 0 && sb > 0) || sa > max_rel_se * va || sb > max_rel_se * vb) continue;
        const double z = (va - vb) / std::hypot(sa, sb);
        out.chi2 += z * z;
        out.max_abs_z = std::max(out.max_abs_z, std::fabs(z));
        out.z.push_back({(static_cast<double>(i) + 0.5) * a.dr_cm * 10, z});
        ++out.bins;
    }
    out.p = out.bins > 0 ? chi_square_p(out.chi2, out.bins) : 1.0;
    out.rd_z = (a.rd_total[c] - b.rd_total[c]) / std::hypot(a.rd_total_se[c], b.rd_total_se[c]);
    return out;
}

}  // namespace

std::map<std::string, std::string> engine_tables(const ExperimentRun& r,
                                                 std::vector<Metric>& metrics) {
    std::map<std::string, std::string> files;
    const Experiment& e = r.exp;
    if (e.volpath.enabled)
        for (const auto& m : e.materials)
            for (int c = 0; c < 3; ++c) {
                const ChannelNode* n = find_node(r, m.label, c, "volpath");
                const volpath::PencilLayout L{n->grid.nr};
                const std::string base = m.label + "." + kChannelNames[c] + ".volpath.";
                metrics.push_back(
                    {base + "Rd", "1", n->vresult.mean[L.rd()], n->vresult.se[L.rd()], true, 0});
                metrics.push_back({base + "Rd_single", "1", n->vresult.mean[L.rd_ss()],
                                   n->vresult.se[L.rd_ss()], true, 0});
                if (m.medium.total_thickness_cm() < 1e8)
                    metrics.push_back({base + "Tt", "1", n->vresult.mean[L.tt()],
                                       n->vresult.se[L.tt()], true, 0});
            }
    if (e.crossval.enabled) {
        std::ostringstream sum, zs;
        sum << "material,layers,channel,bins,chi2,p_value,max_abs_z,Rd_mcml,Rd_mcml_se,Rd_volpath,"
               "Rd_volpath_se,Rd_z,Tt_mcml,Tt_mcml_se,Tt_volpath,Tt_volpath_se,Tt_z,volpath_mode\n";
        zs << "material,channel,r_mid_mm,z\n";
        for (const auto& m : e.materials) {
            const RadialProfile vp = volpath_profile(r, m.label, false);
            const RadialProfile mc = material_profile(r, m.label);
            for (int c = 0; c < 3; ++c) {
                const CrossRow x = crossval(vp, mc, c, e.crossval.max_rel_se);
                sum << m.label << ',' << 1 + m.medium.lower_layers.size() << ',' << kChannelNames[c]
                    << ',' << x.bins << ',' << format_g(x.chi2, 10) << ',' << format_g(x.p, 10)
                    << ',' << format_g(x.max_abs_z, 10) << ',' << format_g(mc.rd_total[c], 10)
                    << ',' << format_g(mc.rd_total_se[c], 10) << ',' << format_g(vp.rd_total[c], 10)
                    << ',' << format_g(vp.rd_total_se[c], 10) << ',' << format_g(x.rd_z, 10) << ',';
                // Transmittance of finite slabs (empty for half-spaces).
                if (m.medium.total_thickness_cm() < 1e8) {
                    const mcml::RunResult& mr = find_node(r, m.label, c, "main")->result;
                    const ChannelNode* vn = find_node(r, m.label, c, "volpath");
                    const volpath::PencilLayout VL{vn->grid.nr};
                    const double tm = mr.mean(mr.layout.tt), tm_se = mr.se[mr.layout.tt];
                    const double tv = vn->vresult.mean[VL.tt()], tv_se = vn->vresult.se[VL.tt()];
                    sum << format_g(tm, 10) << ',' << format_g(tm_se, 10) << ',' << format_g(tv, 10)
                        << ',' << format_g(tv_se, 10) << ','
                        << format_g((tv - tm) / std::hypot(tm_se, tv_se), 10) << ',';
                } else {
                    sum << ",,,,,";
                }
                sum << e.volpath.mode << '\n';
                for (const auto& [rm, z] : x.z)
                    zs << m.label << ',' << kChannelNames[c] << ',' << format_g(rm, 10) << ','
                       << format_g(z, 10) << '\n';
            }
        }
        files["crossval/summary.csv"] = sum.str();
        files["crossval/z_scores.csv"] = zs.str();
    }
    if (e.pencil.enabled) {
        std::ostringstream err;
        err << "model,material,channel,compared_with,rel_l2_rR,noise_floor_rel_l2_rR,Rd_model,"
               "Rd_reference,Rd_reference_se,Rd_rel_error,Rd_z,note\n";
        for (const auto& m : e.materials) {
            const MaterialPencil p = pencil_data(r, m, true);
            files["pencil/" + m.label + ".csv"] = pencil_csv(p, e.pencil.models.names());
            for (int c = 0; c < 3; ++c) {
                const Reference& f = p.ref[static_cast<size_t>(c)];
                for (const ModelCurve& mc : p.models[static_cast<size_t>(c)]) {
                    const std::vector<double>& ref = mc.single ? f.all : f.ms;
                    const std::vector<double>& rse = mc.single ? f.all_se : f.ms_se;
                    const double rd = mc.single ? f.rd : f.rd_ms;
                    const double rd_se = mc.single ? f.rd_se : f.rd_ms_se;
                    err << mc.name << ',' << m.label << ',' << kChannelNames[c] << ','
                        << (mc.single ? "volpath_total" : "volpath_multiple_scattering");
                    if (!mc.error.empty()) {
                        err << ",,,,,,,,\"" << mc.error << "\"\n";
                        continue;
                    }
                    std::vector<double> plus(ref.size());
                    for (size_t k = 0; k < ref.size(); ++k) plus[k] = ref[k] + rse[k];
                    const RelL2 l2 = rel_l2_rr(p.bins, mc.v, ref, rse);
                    const std::string mb =
                        m.label + "." + kChannelNames[c] + ".model." + mc.name + ".";
                    metrics.push_back({mb + "Rd", "1", mc.rd, 0, false, 1e-9});
                    // Stochastic: the reference is a Monte Carlo estimate, so a reseeded
                    // reference moves the error by about this standard error.
                    metrics.push_back({mb + "rel_l2_rR", "1", l2.value, l2.se, true, 0});
                    err << ',' << format_g(l2.value, 10) << ','
                        << format_g(rel_l2_rr(p.bins, plus, ref).value, 10) << ','
                        << format_g(mc.rd, 10) << ',' << format_g(rd, 10) << ','
                        << format_g(rd_se, 10) << ',' << format_g((mc.rd - rd) / rd, 10) << ','
                        << format_g((mc.rd - rd) / rd_se, 10) << ",\n";
                }
            }
        }
        files["pencil/errors.csv"] = err.str();
    }
    if (e.efficiency.enabled) {
        for (const auto& label : e.efficiency.materials) {
            std::ostringstream os;
            os << "engine,channel,batches,paths,seconds,Rd,Rd_se,rel_se,efficiency_per_s\n";
            for (int c = 0; c < 3; ++c) {
                const ChannelNode* mc = find_node(r, label, c, "main");
                const ChannelNode* vp = find_node(r, label, c, "volpath");
                std::uint64_t b = 0;
                for (const auto& p : mc->result.history) {
                    if (++b < 2 || !(p.value > 0)) continue;
                    const double rel = p.se / p.value;
                    os << "mcml," << kChannelNames[c] << ',' << b << ',' << p.samples << ','
                       << format_g(p.seconds, 10) << ',' << format_g(p.value, 10) << ','
                       << format_g(p.se, 10) << ',' << format_g(rel, 10) << ','
                       << format_g(1 / (rel * rel * p.seconds), 10) << '\n';
                }
                b = 0;
                for (const auto& p : vp->vresult.history) {
                    if (++b < 2 || !(p.value > 0)) continue;
                    const double rel = p.se / p.value;
                    os << "volpath " << e.volpath.mode << ',' << kChannelNames[c] << ',' << b << ','
                       << p.samples << ',' << format_g(p.seconds, 10) << ','
                       << format_g(p.value, 10) << ',' << format_g(p.se, 10) << ','
                       << format_g(rel, 10) << ',' << format_g(1 / (rel * rel * p.seconds), 10)
                       << '\n';
                }
            }
            files["efficiency/" + label + ".csv"] = os.str();
        }
    }
    return files;
}

std::vector<PlotRequest> engine_plots(const ExperimentRun& r) {
    std::vector<PlotRequest> out;
    const Experiment& e = r.exp;
    if (e.crossval.enabled) {
        out.push_back(
            {"{\"kind\": \"z_histogram\", \"csv\": \"crossval/z_scores.csv\", \"title\": " +
                 json_string(e.name) + ", \"out\": \"plots/crossval_z\"}",
             {"crossval/z_scores.csv"},
             {"crossval", "z histogram", "plots/crossval_z",
              "Per-bin z-scores of MCML against the path tracer, all materials and "
              "channels pooled, with the standard normal density they should follow "
              "(left), and against radius per material (right)."}});
    }
    if (e.pencil.enabled) {
        std::string models = "[";
        for (size_t i = 0; i < e.pencil.models.names().size(); ++i)
            models += (i ? ", " : "") + json_string(e.pencil.models.names()[i]);
        models += "]";
        for (const auto& m : e.materials) {
            const std::string csv = "pencil/" + m.label + ".csv";
            const std::string stem = "plots/pencil_" + m.label;
            out.push_back(
                {"{\"kind\": \"pencil\", \"csv\": " + json_string(csv) + ", \"models\": " + models +
                     ", \"title\": " + json_string(m.label) + ", \"out\": " + json_string(stem) +
                     "}",
                 {csv},
                 {"pencil", m.label, stem,
                  m.label + ": R_d(r) of MCML (dots) and the path tracer (line, +-2 SE band; "
                            "dashed: its multiple-scattering part) and of every analytic model, "
                            "per channel, on linear, logarithmic and square-root axes and as "
                            "r R_d(r) [Bitterli13 §3.6.3]. Every curve is per incident photon "
                            "(models without the entry Fresnel factor are multiplied by 1 - Rsp) "
                            "and averaged over the same annuli."}});
        }
    }
    if (e.efficiency.enabled)
        for (const auto& m : e.efficiency.materials) {
            const std::string csv = "efficiency/" + m + ".csv";
            const std::string stem = "plots/efficiency_" + m;
            out.push_back({"{\"kind\": \"efficiency\", \"csv\": " + json_string(csv) +
                               ", \"title\": " + json_string(m) +
                               ", \"out\": " + json_string(stem) + "}",
                           {csv},
                           {"efficiency", m, stem,
                            m + ": relative standard error of the total diffuse reflectance "
                                "against wall time for both engines, per channel, and their "
                                "efficiency 1 / (relative variance x time). Each run had every "
                                "core to itself."}});
        }
    return out;
}

void engine_report(const ExperimentRun& r, const std::map<std::string, std::string>& files,
                   const PlotResult& plots, std::ostringstream& os) {
    const Experiment& e = r.exp;
    if (e.crossval.enabled) {
        os << "<h2 id=\"crossval\">MCML against the path tracer</h2>\n<p>The two engines share "
              "no transport code. Per material and channel: the chi-square of the per-bin "
              "z-scores (bins where both relative standard errors are below "
           << e.crossval.max_rel_se
           << "), its p-value, the largest |z|, and the z-score of the totals. The path tracer "
              "runs in its "
           << e.volpath.mode
           << " mode. Tables: <a href=\"crossval/summary.csv\">summary.csv</a>, <a "
              "href=\"crossval/z_scores.csv\">z_scores.csv</a>.</p>\n";
        csv_table(os, files.at("crossval/summary.csv"), "Cross-validation");
        figures(os, plots, "crossval");
    }
    if (e.pencil.enabled) {
        os << "<h2 id=\"pencil\">Pencil beam: analytic profiles against ground truth</h2>\n<p>"
              "Each model's relative L2 error of r R<sub>d</sub>(r) against the path tracer (the "
              "noise floor is the same distance for the tracer's own +1 SE), and its error in "
              "total diffuse reflectance. Like with like: models without single scattering are "
              "compared with the multiple-scattering part (paths with two or more scattering "
              "events), models without the entry Fresnel factor are multiplied by 1 - "
              "R<sub>sp</sub>. Tables: <a href=\"pencil/errors.csv\">errors.csv</a>, "
              "pencil/&lt;material&gt;.csv.</p>\n";
        csv_table(os, files.at("pencil/errors.csv"), "Model errors");
        figures(os, plots, "pencil");
    }
    if (e.efficiency.enabled) {
        os << "<h2 id=\"efficiency\">Both engines against run time</h2>\n<p>Tables: ";
        for (const auto& m : e.efficiency.materials)
            os << "<a href=\"efficiency/" << esc(m) << ".csv\">" << esc(m) << ".csv</a> ";
        os << "</p>\n";
        figures(os, plots, "efficiency");
    }
}

}  // namespace ssslab::runner
