#include "experiments/runner/report.h"

#include "core/format.h"
#include "core/provenance.h"
#include "experiments/runner/engines.h"
#include "experiments/runner/kernel_study.h"
#include "experiments/runner/nodes.h"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <map>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace ssslab::runner {

std::string esc(const std::string& s) {
    std::string o;
    for (char c : s) {
        switch (c) {
            case '&':
                o += "&amp;";
                break;
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '"':
                o += "&quot;";
                break;
            default:
                o += c;
        }
    }
    return o;
}

std::string csv_field(const std::string& v) {
    if (v.find_first_of(",\"\n") == std::string::npos) return v;
    std::string q = "\"";
    for (char c : v) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
    return q + "\"";
}

namespace {

const char* kStyle = R"CSS(
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222;
       line-height: 1.45; padding: 0 1em; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
.meta { color: #555; font-size: 0.92em; }
table { border-collapse: collapse; font-size: 0.86em; margin: 0.8em 0; }
th, td { border: 1px solid #ddd; padding: 0.25em 0.55em; text-align: right; }
th { background: #f3f3f3; }
td.l, th.l { text-align: left; }
tr.R td.ch { color: #d62728; } tr.G td.ch { color: #2ca02c; } tr.B td.ch { color: #1f77b4; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; }
pre { background: #f7f7f7; padding: 0.8em; overflow-x: auto; font-size: 0.82em; }
.note { background: #fff8e0; border-left: 4px solid #e0b000; padding: 0.5em 0.8em; }
code { font-size: 0.95em; }
img.panel { width: 180px; image-rendering: pixelated; border: 1px solid #ddd; }
table.panels td { border: none; font-size: 0.8em; vertical-align: top; }
nav#contents { background: #f7f7f7; border: 1px solid #ddd; padding: 0.5em 1em; font-size: 0.9em;
               margin-top: 1em; }
nav#contents > ol { columns: 2; }
nav#contents ol { margin: 0.2em 0; padding-left: 1.6em; }
nav#contents li { break-inside: avoid; }
div.wide { max-width: 100%; overflow-x: auto; }
table.prov { font-size: 0.8em; }
table.prov td { white-space: nowrap; }
table.prov td.w { white-space: normal; overflow-wrap: anywhere; }
div.metrics { display: flex; flex-wrap: wrap; gap: 0 1.6em; align-items: flex-start; }
table.metrics caption { text-align: left; padding-bottom: 0.2em; }
table.metrics caption span { color: #666; }
div.metrics details { flex-basis: 100%; margin: 0.4em 0; }
th.R { color: #d62728; } th.G { color: #2ca02c; } th.B { color: #1f77b4; }
)CSS";

// Marks the page once every image has loaded (or failed): the headless-browser test reads it.
const char* kImageCheck = R"JS(
<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var bad = imgs.filter(function (i) { return !i.complete || i.naturalWidth === 0; });
  document.body.setAttribute('data-images', String(imgs.length));
  document.body.setAttribute('data-images-ok', bad.length === 0 ? 'yes' : 'no');
  bad.forEach(function (i) { i.insertAdjacentHTML('afterend',
      '<p class="note">missing image: ' + i.getAttribute('src') + '</p>'); });
});
</script>
)JS";

const ChannelNode* node(const ExperimentRun& r, const std::string& m, int c, const char* role) {
    for (const auto& n : r.nodes)
        if (n.material == m && n.channel == c && n.role == role) return &n;
    return nullptr;
}

}  // namespace

void figures(std::ostringstream& os, const PlotResult& p, const std::string& section) {
    for (const auto& f : p.plots) {
        if (f.section != section) continue;
        os << "<figure><a href=\"" << esc(f.stem) << ".svg\"><img src=\"" << esc(f.stem)
           << ".png\" alt=\"" << esc(f.title) << "\"></a><figcaption>" << esc(f.caption)
           << " (<a href=\"" << esc(f.stem) << ".svg\">SVG</a>)</figcaption></figure>\n";
    }
}

std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        std::vector<std::string> row;
        std::string cell;
        bool quoted = false;
        for (char ch : line) {
            if (ch == '"')
                quoted = !quoted;
            else if (ch == ',' && !quoted)
                row.push_back(cell), cell.clear();
            else
                cell += ch;
        }
        row.push_back(cell);
        rows.push_back(row);
    }
    return rows;
}

namespace {

size_t column(const std::vector<std::string>& header, const char* name) {
    for (size_t i = 0; i < header.size(); ++i)
        if (header[i] == name) return i;
    return header.size();
}

std::string cell_num(const std::string& v, int digits = 4) {
    if (v.empty()) return "";
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    return *end == '\0' ? format_g(x, digits) : esc(v);
}

// Rows grouped by a key with one value per channel: "key -> R, G, B".
void channel_table(std::ostringstream& os, const std::string& csv,
                   const std::vector<const char*>& keys, const char* value,
                   const std::vector<const char*>& extra_sum, const char* title) {
    const auto rows = parse_csv(csv);
    if (rows.size() < 2) return;
    const auto& h = rows[0];
    const size_t ch = column(h, "channel"), v = column(h, value);
    std::vector<std::string> order;
    std::map<std::string, std::array<std::string, 3>> vals;
    std::map<std::string, std::vector<std::string>> key_cells;
    std::map<std::string, std::vector<double>> sums;
    for (size_t i = 1; i < rows.size(); ++i) {
        const auto& row = rows[i];
        std::string key;
        std::vector<std::string> kc;
        for (const char* k : keys) {
            const size_t c = column(h, k);
            kc.push_back(c < row.size() ? row[c] : "");
            key += kc.back() + "|";
        }
        if (!vals.count(key))
            order.push_back(key), key_cells[key] = kc, sums[key].assign(extra_sum.size(), 0.0);
        const int channel = row[ch] == "R" ? 0 : row[ch] == "G" ? 1 : 2;
        vals[key][static_cast<size_t>(channel)] = v < row.size() ? row[v] : "";
        for (size_t e = 0; e < extra_sum.size(); ++e) {
            const size_t c = column(h, extra_sum[e]);
            if (c < row.size()) sums[key][e] += std::strtod(row[c].c_str(), nullptr);
        }
    }
    os << "<p><b>" << title << "</b></p>\n<div class=\"wide\"><table>\n<tr>";
    for (const char* k : keys) os << "<th class=\"l\">" << esc(k) << "</th>";
    os << "<th>R</th><th>G</th><th>B</th>";
    for (const char* e : extra_sum) os << "<th>" << esc(e) << " (sum RGB)</th>";
    os << "</tr>\n";
    for (const auto& key : order) {
        os << "<tr>";
        for (const auto& kc : key_cells[key]) os << "<td class=\"l\">" << esc(kc) << "</td>";
        for (const auto& x : vals[key]) os << "<td>" << cell_num(x) << "</td>";
        for (double x : sums[key]) os << "<td>" << format_g(x, 3) << "</td>";
        os << "</tr>\n";
    }
    os << "</table></div>\n";
}

}  // namespace

// A whole CSV as a table (string columns left-aligned, numbers to 4 digits).
void csv_table(std::ostringstream& os, const std::string& csv, const char* title) {
    const auto rows = parse_csv(csv);
    if (rows.size() < 2) return;
    os << "<p><b>" << title << "</b></p>\n<div class=\"wide\"><table>\n<tr>";
    for (const auto& h : rows[0]) os << "<th>" << esc(h) << "</th>";
    os << "</tr>\n";
    for (size_t i = 1; i < rows.size(); ++i) {
        os << "<tr>";
        for (const auto& c : rows[i]) {
            char* end = nullptr;
            std::strtod(c.c_str(), &end);
            const bool number = !c.empty() && *end == '\0';
            os << (number ? "<td>" : "<td class=\"l\">") << cell_num(c) << "</td>";
        }
        os << "</tr>\n";
    }
    os << "</table></div>\n";
}

namespace {

void study_section(std::ostringstream& os, const StudyOutput& so, const PlotResult& plots) {
    const KernelStudySpec& s = *so.spec;
    const std::string dir = "kernels/" + s.name + "/";
    os << "<h3 id=\"study-" << esc(s.name) << "\">Kernel study <code>" << esc(s.name)
       << "</code></h3>\n<p class=\"meta\">" << esc(so.summary) << " &middot; "
       << (so.computed_now ? "computed in this run" : "reused from the cache")
       << " &middot; key <code>" << so.key.substr(0, 16) << "</code> &middot; tables: ";
    for (const auto& [name, content] : so.files)
        if (name.size() > 4 && name.substr(name.size() - 4) == ".csv")
            os << "<a href=\"" << esc(dir + name) << "\">" << esc(name) << "</a> ";
    os << "</p>\n<p>Models: ";
    for (const auto& m : s.models) os << "<code>" << esc(m.text) << "</code> ";
    os << ". Every kernel is built on the thesis's grid of each material (cells of dr = min MFP "
          "/ 20 over 32 max MFP"
       << (s.refine > 1 ? ", refined " + std::to_string(s.refine) + " times" : "")
       << ") from the ground-truth profile normalised to unit L1, as Freude14 §6.2 does.</p>\n";
    if (so.files.count("kernels.csv"))
        channel_table(os, so.files.at("kernels.csv"), {"material", "model"}, "kernel_rms",
                      {"build_s", "l1_error"}, "Kernel-space RMS per channel (unit-L1 kernels)");
    if (so.files.count("comparison.csv")) {
        channel_table(os, so.files.at("comparison.csv"), {"material", "model"}, "normalised", {},
                      "Kernel-space RMS normalised as Freude14 Table 6.3 (by the entry the "
                      "thesis maps to 1: Ketchup, manual, B)");
        channel_table(os, so.files.at("comparison.csv"), {"material", "model"}, "thesis_normalised",
                      {}, "Freude14 Table 6.3 (the thesis's numbers)");
        channel_table(os, so.files.at("comparison.csv"), {"material", "model"}, "ratio", {},
                      "Ratio ours / thesis");
        channel_table(os, so.files.at("comparison.csv"), {"material", "model"}, "over_svd1", {},
                      "Kernel-space RMS over SVD rank-1's, per material and channel (ours): "
                      "independent of the table's normalisation and of the grid's cell count");
        channel_table(os, so.files.at("comparison.csv"), {"material", "model"}, "thesis_over_svd1",
                      {}, "The same from Freude14 Table 6.3");
        channel_table(os, so.files.at("comparison.csv"), {"material", "model"}, "ratio_over_svd1",
                      {}, "Ratio ours / thesis of the RMS over SVD rank-1's");
    }
    if (so.files.count("properties.csv"))
        csv_table(os, so.files.at("properties.csv"),
                  "Properties of the models as Freude14 Table 5.1, measured: rank (a separable "
                  "kernel has rank 1), 1D convolutions per pass pair, closed form (no "
                  "optimisation), build time per kernel (one channel), mean kernel-space RMS, "
                  "largest energy (L1) error, mean image-space RMS over signals, materials and "
                  "channels at full resolution and with taps");
    if (so.files.count("image.csv"))
        channel_table(os, so.files.at("image.csv"), {"material", "signal", "model", "sampling"},
                      "rms", {}, "Image-space RMS per channel against the exact 2D convolution");
    if (so.files.count("image_vs_reference.csv"))
        channel_table(os, so.files.at("image_vs_reference.csv"), {"material", "signal", "model"},
                      "rms", {},
                      ("Image-space RMS against the result of " + s.reference +
                       " (full resolution): how close each model comes to it")
                          .c_str());
    for (const auto& f : plots.plots)
        if (f.section == "study:" + s.name)
            os << "<figure><a href=\"" << esc(f.stem) << ".svg\"><img src=\"" << esc(f.stem)
               << ".png\" alt=\"" << esc(f.title) << "\"></a><figcaption>" << esc(f.caption)
               << "</figcaption></figure>\n";
    // Image panels: input, exact, then each model and its difference (normalised across the
    // models of a signal).
    std::map<std::string, std::vector<std::string>> panels;  // images/<material>/<signal>/ -> files
    for (const auto& [name, content] : so.files)
        if (name.rfind("images/", 0) == 0) {
            const size_t slash = name.rfind('/');
            panels[name.substr(0, slash + 1)].push_back(name.substr(slash + 1));
        }
    for (const auto& panel : panels) {
        const std::string& folder = panel.first;  // captured below: no structured binding
        const std::vector<std::string>& names = panel.second;
        os << "<p><b>" << esc(folder.substr(7))
           << "</b> (differences scaled to the largest "
              "difference among the models)</p>\n<table class=\"panels\"><tr>";
        auto cell = [&](const std::string& file, const std::string& caption) {
            os << "<td class=\"l\"><img class=\"panel\" src=\"" << esc(dir + folder + file)
               << "\" alt=\"" << esc(caption) << "\"><br>" << esc(caption) << "</td>";
        };
        cell("input.png", "input");
        cell("exact.png", "exact (2D)");
        int col = 2;
        for (const auto& n : names) {
            if (n == "input.png" || n == "exact.png" || n.find("_diff.png") != std::string::npos)
                continue;
            const std::string label = n.substr(0, n.size() - 4);
            if (col++ % 6 == 0) os << "</tr><tr>";
            cell(n, label);
            cell(label + "_diff.png", label + " |diff|");
            ++col;
        }
        os << "</tr></table>\n";
    }
}

}  // namespace

std::string with_error(double value, double se) {
    if (!(se > 0) || !std::isfinite(se)) return format_g(value, 6);
    const int digits = std::max(0, 1 - static_cast<int>(std::floor(std::log10(se))));
    char buf[80];
    if (digits > 12)
        std::snprintf(buf, sizeof buf, "%.3g \u00b1 %.2g", value, se);
    else
        std::snprintf(buf, sizeof buf, "%.*f \u00b1 %.*f", digits, value, digits, se);
    return buf;
}

namespace {

// The metrics as small tables instead of one flat list: a name "<row>.<R|G|B>.<quantity>" (the
// row a material, a scene or a study entry) goes into its quantity's table, in the row's line
// and the channel's column. Names without a channel, "<row>.<quantity>": a quantity whose rows
// all end in one of a few variants ("<entry>.full", "<entry>.taps17") gets a table with a
// column per variant (where that makes fewer rows); the others (a material's grid: nr, dr) share
// one table with a column per quantity. Tables of more than 40 rows are folded. Every value keeps
// its name as its title.
void metrics_tables(std::ostringstream& os, const std::vector<Metric>& ms) {
    struct Table {
        std::string caption;  // the quantity ("" for the shared table)
        std::vector<std::string> columns, rows;
        std::map<std::string, std::map<std::string, const Metric*>> cells;  // row -> column -> m
        bool channels = false;
        void add(const std::string& row, const std::string& col, const Metric* m) {
            if (!cells.count(row)) rows.push_back(row);
            if (std::find(columns.begin(), columns.end(), col) == columns.end())
                columns.push_back(col);
            cells[row][col] = m;
        }
    };
    std::vector<Table> tables;
    auto table = [&](const std::string& caption, bool channels) -> Table& {
        for (Table& t : tables)
            if (t.caption == caption && t.channels == channels) return t;
        tables.push_back({caption, {}, {}, {}, channels});
        if (channels) tables.back().columns = {"R", "G", "B"};
        return tables.back();
    };
    // Channel-less metrics by quantity: (row, metric) in order.
    std::vector<std::pair<std::string, std::vector<std::pair<std::string, const Metric*>>>> plain;
    for (const Metric& m : ms) {
        std::vector<std::string> part;
        std::stringstream in(m.name);
        for (std::string x; std::getline(in, x, '.');) part.push_back(x);
        size_t ch = 1;
        while (ch + 1 < part.size() && part[ch] != "R" && part[ch] != "G" && part[ch] != "B") ++ch;
        auto join = [&](size_t from, size_t to) {
            std::string o;
            for (size_t i = from; i < to; ++i) o += (i > from ? "." : "") + part[i];
            return o;
        };
        if (part.size() >= 3 && ch + 1 < part.size()) {
            table(join(ch + 1, part.size()), true).add(join(0, ch), part[ch], &m);
            continue;
        }
        const std::string q = part.size() < 2 ? m.name : part.back();
        const std::string row = part.size() < 2 ? "" : join(0, part.size() - 1);
        auto it =
            std::find_if(plain.begin(), plain.end(), [&](const auto& x) { return x.first == q; });
        if (it == plain.end()) it = plain.insert(plain.end(), {q, {}});
        it->second.emplace_back(row, &m);
    }
    for (const auto& [q, entries] : plain) {
        std::vector<std::string> variants, heads;
        bool split = true;
        for (const auto& [row, m] : entries) {
            const size_t dot = row.rfind('.');
            if (dot == std::string::npos) {
                split = false;
                break;
            }
            const std::string v = row.substr(dot + 1), h = row.substr(0, dot);
            if (std::find(variants.begin(), variants.end(), v) == variants.end())
                variants.push_back(v);
            if (std::find(heads.begin(), heads.end(), h) == heads.end()) heads.push_back(h);
        }
        if (split && variants.size() >= 2 && variants.size() <= 6 &&
            heads.size() < entries.size()) {
            Table& t = table(q, false);
            for (const auto& [row, m] : entries) {
                const size_t dot = row.rfind('.');
                t.add(row.substr(0, dot), row.substr(dot + 1), m);
            }
        } else {
            Table& t = table("", false);
            for (const auto& [row, m] : entries) t.add(row, q, m);
        }
    }
    auto value = [](const Metric* m) {
        if (!m) return std::string("<td></td>");
        return "<td title=\"" + esc(m->name) + "\">" +
               (m->stochastic ? with_error(m->value, m->se) : format_g(m->value, 10)) + "</td>";
    };
    auto kind = [](const std::vector<const Metric*>& v) {
        std::vector<std::string> kinds;
        for (const Metric* m : v) {
            std::string k = m->stochastic ? "&plusmn; standard error"
                                          : "rel. tol. " + format_g(m->tolerance, 6);
            if (std::find(kinds.begin(), kinds.end(), k) == kinds.end()) kinds.push_back(k);
        }
        std::string o;
        for (const auto& k : kinds) o += (o.empty() ? "" : ", ") + k;
        return o;
    };
    auto unit_of = [](const std::vector<const Metric*>& v) {
        const std::string u = v.empty() ? "" : v.front()->unit;
        return u.empty() || u == "1" ? std::string() : " [" + esc(u) + "]";
    };
    // The shared table first (a material's grid), then the tables in order of appearance.
    std::stable_partition(tables.begin(), tables.end(),
                          [](const Table& t) { return t.caption.empty(); });
    os << "<div class=\"metrics\">\n";
    for (const Table& t : tables) {
        std::vector<const Metric*> all;
        for (const auto& [row, cols] : t.cells)
            for (const auto& [col, m] : cols) all.push_back(m);
        const bool fold = t.rows.size() > 40;
        if (fold)
            os << "<details><summary><b>" << esc(t.caption.empty() ? "per material" : t.caption)
               << "</b>: " << all.size() << " values in " << t.rows.size() << " rows</summary>\n";
        os << "<table class=\"metrics\"><caption>";
        if (t.caption.empty())
            os << "<b>per material</b>";
        else
            os << "<b>" << esc(t.caption) << "</b>" << unit_of(all) << " <span>(" << kind(all)
               << ")</span>";
        os << "</caption>\n<tr><th class=\"l\"></th>";
        for (const auto& col : t.columns) {
            if (t.channels) {
                os << "<th class=\"" << col << "\">" << col << "</th>";
                continue;
            }
            std::vector<const Metric*> c;
            for (const auto& row : t.rows)
                if (t.cells.at(row).count(col)) c.push_back(t.cells.at(row).at(col));
            os << "<th title=\"" << kind(c) << "\">" << esc(col)
               << (t.caption.empty() ? unit_of(c) : "") << "</th>";
        }
        os << "</tr>\n";
        for (const auto& row : t.rows) {
            os << "<tr><td class=\"l\">" << esc(row) << "</td>";
            for (const auto& col : t.columns) {
                const auto& r = t.cells.at(row);
                os << value(r.count(col) ? r.at(col) : nullptr);
            }
            os << "</tr>\n";
        }
        os << "</table>\n" << (fold ? "</details>\n" : "");
    }
    os << "</div>\n";
}

// A flip viewer (study.h FlipViewer); flip_viewer_script drives it.
void flip_viewer_html(std::ostringstream& os, const FlipViewer& v) {
    os << "<div class=\"flip\" id=\"" << esc(v.id) << "\">\n<p class=\"flipbar\">";
    for (size_t i = 0; i < v.images.size(); ++i)
        os << "<button type=\"button\" data-src=\"" << esc(v.images[i].path) << "\" data-diff=\""
           << esc(v.images[i].diff) << "\"" << (i == v.first ? " class=\"on\"" : "") << ">"
           << esc(v.images[i].caption) << "</button> ";
    const FlipViewer::Image* first = v.first < v.images.size() ? &v.images[v.first] : nullptr;
    os << "<br><label>exposure <input type=\"range\" class=\"exposure\" min=\"-4\" "
          "max=\"4\" step=\"0.5\" value=\"0\"> <span class=\"ev\">0</span> "
          "stops</label> <label><input type=\"checkbox\" class=\"diffmode\"> "
          "difference to "
       << esc(v.diff_of)
       << "</label> (keys: left / right flip, d difference)</p>\n<img class=\"view\" src=\""
       << (first ? esc(first->path) : "") << "\" alt=\"" << esc(v.what)
       << "\" style=\"width:" << v.width_px
       << "px;image-rendering:pixelated\">\n<p class=\"caption\">" << esc(v.what)
       << "; showing <span class=\"which\">" << (first ? esc(first->caption) : "")
       << "</span>.</p>\n<div class=\"cuts\">";
    for (const FlipViewer::Image& e : v.images)
        os << "<figure><img src=\"" << esc(e.cut) << "\" alt=\"cut-out " << esc(e.caption)
           << "\"><br><img src=\"" << esc(e.cut_diff) << "\" alt=\"difference " << esc(e.caption)
           << "\"><br>" << esc(e.caption) << "</figure>";
    os << "</div>\n</div>\n";
}

// The flip viewers' script and style: buttons flip between a viewer's images, a checkbox shows
// the differences, a slider sets the exposure, the arrow keys and d do the same.
const char* flip_viewer_script() {
    return "<script>\n(function () {\n"
           "  document.querySelectorAll('div.flip').forEach(function (v) {\n"
           "    var img = v.querySelector('img.view'), which = v.querySelector('span.which');\n"
           "    var buttons = Array.prototype.slice.call(v.querySelectorAll('button'));\n"
           "    var range = v.querySelector('input.exposure'), ev = v.querySelector('span.ev');\n"
           "    var diff = v.querySelector('input.diffmode');\n"
           "    var at = Math.max(0, buttons.findIndex(function (b) { return b.className === "
           "'on'; }));\n"
           "    function show(i) {\n"
           "      at = (i + buttons.length) % buttons.length;\n"
           "      buttons.forEach(function (b, k) { b.className = k === at ? 'on' : ''; });\n"
           "      var b = buttons[at];\n"
           "      img.src = diff.checked ? b.dataset.diff : b.dataset.src;\n"
           "      which.textContent = b.textContent + (diff.checked ? ' (difference)' : '');\n"
           "      v.dataset.showing = img.getAttribute('src');\n"
           "    }\n"
           "    buttons.forEach(function (b, k) { b.addEventListener('click', function () { "
           "show(k); }); });\n"
           "    diff.addEventListener('change', function () { show(at); });\n"
           "    range.addEventListener('input', function () {\n"
           "      ev.textContent = range.value;\n"
           "      img.style.filter = 'brightness(' + Math.pow(2, range.value) + ')';\n"
           "    });\n"
           "    v.tabIndex = 0;\n"
           "    v.addEventListener('keydown', function (e) {\n"
           "      if (e.key === 'ArrowRight') show(at + 1);\n"
           "      else if (e.key === 'ArrowLeft') show(at - 1);\n"
           "      else if (e.key === 'd') { diff.checked = !diff.checked; show(at); }\n"
           "    });\n"
           "    v.dataset.ready = 'yes';\n"
           "  });\n"
           "})();\n</script>\n"
           "<style>div.flip button.on { font-weight: bold; background: #dde; } div.cuts { "
           "display: flex; flex-wrap: wrap; gap: 4px; } div.cuts figure { margin: 0; width: "
           "128px; font-size: 80%; } div.cuts img { width: 128px; display: block; "
           "image-rendering: pixelated; }</style>\n";
}

// A plugin study's section (study.h): its heading (h2, subsections h3), paragraphs, the figures
// of its plots, tables, figures, flip viewers and subsections, every text escaped. Says whether
// it holds a flip viewer.
bool study_section_html(std::ostringstream& os, const StudySection& s, const PlotResult& plots,
                        int level = 2) {
    os << "<h" << level << " id=\"" << esc(s.id) << "\">" << esc(s.title) << "</h" << level
       << ">\n";
    for (const std::string& p : s.paragraphs) os << "<p>" << esc(p) << "</p>\n";
    if (!s.plot_section.empty()) {
        if (!plots.problem.empty())
            os << "<p class=\"note\">No plots: " << esc(plots.problem) << "</p>\n";
        figures(os, plots, s.plot_section);
    }
    for (const StudySection::Table& t : s.tables) csv_table(os, t.csv, esc(t.title).c_str());
    for (const StudySection::Figure& f : s.figures)
        os << "<figure><img src=\"" << esc(f.path) << "\" alt=\"" << esc(f.caption)
           << "\" style=\"max-width:256px\"><figcaption>" << esc(f.caption)
           << "</figcaption></figure>\n";
    bool viewers = !s.viewers.empty();
    for (const FlipViewer& v : s.viewers) flip_viewer_html(os, v);
    for (const StudySection& sub : s.subsections)
        viewers = study_section_html(os, sub, plots, level + 1) || viewers;
    return viewers;
}

// A table of contents of the page's sections: every <h2 id> of `body`, with its <h3 id>s.
std::string contents(const std::string& body) {
    struct Entry {
        std::string id, title;
        std::vector<std::pair<std::string, std::string>> subs;
    };
    std::vector<Entry> toc;
    for (size_t at = body.find("<h"); at != std::string::npos; at = body.find("<h", at + 1)) {
        const bool h2 = body.compare(at, 8, "<h2 id=\"") == 0;
        if (!h2 && body.compare(at, 8, "<h3 id=\"") != 0) continue;
        const size_t id0 = at + 8, id1 = body.find('"', id0);
        const size_t t0 = body.find('>', id1) + 1, t1 = body.find(h2 ? "</h2>" : "</h3>", t0);
        if (id1 == std::string::npos || t1 == std::string::npos) break;
        std::string title;  // the heading's text without its tags
        bool tag = false;
        for (size_t i = t0; i < t1; ++i) {
            if (body[i] == '<') tag = true;
            if (!tag) title += body[i];
            if (body[i] == '>') tag = false;
        }
        const std::string id = body.substr(id0, id1 - id0);
        if (h2)
            toc.push_back({id, title, {}});
        else if (!toc.empty())
            toc.back().subs.emplace_back(id, title);
    }
    std::ostringstream os;
    os << "<nav id=\"contents\"><b>Contents</b>\n<ol>\n";
    for (const Entry& e : toc) {
        os << "<li><a href=\"#" << e.id << "\">" << e.title << "</a>";
        if (!e.subs.empty()) {
            os << "<ol>";
            for (const auto& [id, title] : e.subs)
                os << "<li><a href=\"#" << id << "\">" << title << "</a></li>";
            os << "</ol>";
        }
        os << "</li>\n";
    }
    os << "</ol></nav>\n";
    return os.str();
}

}  // namespace

// The artifacts' provenance table: one row per ground-truth run of the experiment.
void provenance_section(std::ostringstream& os, const ExperimentRun& r) {
    // Provenance: columns with one value in every row (engine, budget, stop reason, revision,
    // usually) are said once above the table, so that the table fits the page.
    struct Column {
        const char* head;
        bool left, code;
        std::string (*get)(const ChannelNode&);
    };
    const std::vector<Column> cols = {
        {"engine", true, false,
         [](const ChannelNode& n) {
             return n.provenance.engine + " " + n.provenance.engine_version;
         }},
        {"budget", true, false, [](const ChannelNode& n) { return n.provenance.budget; }},
        {"stopped by", true, false, [](const ChannelNode& n) { return n.provenance.stop_reason; }},
        {"revision", true, true, [](const ChannelNode& n) { return n.provenance.revision; }},
    };
    std::vector<bool> varies(cols.size(), false);
    for (size_t k = 0; k < cols.size(); ++k)
        for (const auto& n : r.nodes)
            if (cols[k].get(n) != cols[k].get(r.nodes.front())) varies[k] = true;
    os << "<h2 id=\"provenance\">Artifacts and provenance</h2>\n<p>Every number above comes from "
          "one of these MCML runs, cached under <code>results/cache/mcml-channel/&lt;key&gt;/"
          "</code> with the key the hash of everything that determines it (medium, grid, "
          "budget, seed, engine version). Table: <a href=\"artifacts.csv\">artifacts.csv</a>.";
    if (!r.nodes.empty()) {
        std::string same;
        for (size_t k = 0; k < cols.size(); ++k)
            if (!varies[k]) {
                const std::string v = esc(cols[k].get(r.nodes.front()));
                same += std::string(same.empty() ? "" : ", ") + cols[k].head + " " +
                        (cols[k].code ? "<code>" + v + "</code>" : v);
            }
        if (!same.empty()) os << " The same for every run: " << same << ".";
    }
    os << "</p>\n<div class=\"wide\"><table class=\"prov\">\n<tr><th class=\"l\">key</th>"
          "<th class=\"l\">material</th><th>ch</th><th class=\"l\">role</th>";
    for (size_t k = 0; k < cols.size(); ++k)
        if (varies[k] && k < 2) os << "<th class=\"l\">" << cols[k].head << "</th>";
    os << "<th>photons</th><th>batches</th><th>seed</th><th>time [s]</th>";
    for (size_t k = 2; k < cols.size(); ++k)
        if (varies[k]) os << "<th class=\"l\">" << cols[k].head << "</th>";
    os << "<th class=\"l\">date (UTC)</th><th class=\"l\">this run</th></tr>\n";
    for (const auto& n : r.nodes) {
        const Provenance& p = n.provenance;
        auto cell = [&](size_t k) {
            if (!varies[k]) return;
            const std::string v = esc(cols[k].get(n));
            os << "<td class=\"l w\">" << (cols[k].code ? "<code>" + v + "</code>" : v) << "</td>";
        };
        std::string date = p.date_utc;  // 2026-12-01T18:35:32Z -> 2026-12-01 18:35:32
        if (date.size() == 20 && date[10] == 'T' && date[19] == 'Z')
            date = date.substr(0, 10) + " " + date.substr(11, 8);
        os << "<tr id=\"a-" << n.key.substr(0, 16) << "\"><td class=\"l\"><code>"
           << n.key.substr(0, 16) << "</code></td><td class=\"l w\">" << esc(n.material)
           << "</td><td>" << kChannelNames[n.channel] << "</td><td class=\"l\">" << n.role
           << "</td>";
        cell(0);
        cell(1);
        os << "<td>" << p.photons << "</td><td>" << p.batches << "</td><td>" << p.seed
           << "</td><td>" << format_g(p.seconds, 4) << "</td>";
        cell(2);
        cell(3);
        os << "<td class=\"l w\">" << esc(date) << "</td><td class=\"l\">"
           << (p.computed_now ? "computed" : "reused") << "</td></tr>\n";
    }
    os << "</table></div>\n";
}

std::string render_report(const ExperimentRun& r, const ReportContent& c) {
    const Experiment& e = r.exp;
    std::ostringstream os;
    os << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
       << esc(e.title) << "</title>\n<style>" << kStyle << "</style>\n</head>\n"
       << "<body data-images-ok=\"pending\">\n";
    os << "<h1>" << esc(e.title) << "</h1>\n<p class=\"meta\">experiment <code>" << esc(e.name)
       << "</code> from <code>" << esc(e.source) << "</code> &middot; "
       << (r.quick ? "<b>--quick</b> (budgets &times; " +
                         format_g(!e.materials.empty() ? e.mcml.quick_factor
                                  : !e.studies.empty() ? e.studies.front().study->quick_factor()
                                                       : 1.0,
                                  6) +
                         ")"
                   : "full budgets")
       << " &middot; seed " << e.seed << " &middot; revision <code>" << esc(git_revision())
       << "</code> &middot; " << esc(utc_now()) << " &middot; " << format_g(r.seconds, 3)
       << " s &middot; " << r.computed << " artifacts computed, " << r.reused
       << " reused from the cache</p>\n";
    const std::string head = os.str();
    os.str("");

    os << "<h2 id=\"description\">Description</h2>\n";
    std::istringstream desc(e.description);
    std::string para, line;
    auto flush = [&] {
        if (!para.empty()) os << "<p>" << esc(para) << "</p>\n";
        para.clear();
    };
    while (std::getline(desc, line)) {
        if (line.find_first_not_of(" \t") == std::string::npos)
            flush();
        else
            para += (para.empty() ? "" : " ") + line;
    }
    flush();
    if (!c.plots.problem.empty())
        os << "<p class=\"note\">No plots: " << esc(c.plots.problem) << "</p>\n";

    if (e.profiles.enabled || e.profile_plots.enabled) {
        os << "<h2 id=\"profiles\">Profiles</h2>\n";
        os << "<p>Per material and RGB channel: MCML's total diffuse reflectance R<sub>d</sub> "
              "(carrying the entry Fresnel factor 1 &minus; R<sub>sp</sub>), the part of it that "
              "left beyond the grid, and the absorbed fraction, each &plusmn; its standard error "
              "from batch statistics. The last column names the artifact behind the row (see "
              "<a href=\"#provenance\">provenance</a>). Tables: <a href=\"summary.csv\">"
              "summary.csv</a>, profiles/&lt;material&gt;.csv (R<sub>d</sub>(r) in 1/"
           << unit_name(e.profiles.unit) << "<sup>2</sup> with standard errors).</p>\n";
        os << "<table>\n<tr><th class=\"l\">material</th><th>ch</th><th>MFP [mm]</th>"
              "<th>albedo</th><th>R<sub>sp</sub></th><th>R<sub>d</sub></th>"
              "<th>R<sub>d</sub> beyond grid</th><th>A</th><th>photons</th><th>grid</th>"
              "<th class=\"l\">artifact</th></tr>\n";
        for (const auto& m : e.materials)
            for (int ch = 0; ch < 3; ++ch) {
                const ChannelNode* n = node(r, m.label, ch, "main");
                const auto& x = n->result;
                const auto& L = x.layout;
                const size_t beyond = L.rd_r + static_cast<size_t>(L.nr);
                os << "<tr class=\"" << kChannelNames[ch] << "\"><td class=\"l\">"
                   << (ch == 0 ? "<a href=\"profiles/" + esc(m.label) + ".csv\">" + esc(m.label) +
                                     "</a>"
                               : "")
                   << "</td><td class=\"ch\">" << kChannelNames[ch] << "</td><td>"
                   << format_g(m.medium.mfp_cm(ch) * 10, 4) << "</td><td>"
                   << format_g(m.medium.albedo(ch), 6) << "</td><td>" << format_g(x.rsp, 4)
                   << "</td><td>" << with_error(x.mean(L.rd), x.se[L.rd]) << "</td><td>"
                   << with_error(x.mean(beyond), x.se[beyond]) << "</td><td>"
                   << with_error(x.mean(L.a), x.se[L.a]) << "</td><td>" << x.photons << "</td><td>"
                   << n->grid.nr << " &times; " << format_g(n->grid.dr_cm * 10, 4)
                   << " mm</td><td class=\"l\"><a href=\"#a-" << n->key.substr(0, 16) << "\"><code>"
                   << n->key.substr(0, 12) << "</code></a></td></tr>\n";
            }
        os << "</table>\n";
        figures(os, c.plots, "profiles");
    }

    if (e.convergence.enabled) {
        os << "<h2 id=\"convergence\">Error against run time</h2>\n<p>The main runs record their "
              "estimate and standard error after every batch, and their whole profile after 4, "
              "8, 16, &hellip; batches; each is compared with an independent reference run (other "
              "random streams) of "
           << format_g(e.convergence.reference_factor, 6) << " times the photons. Tables: ";
        for (const auto& m : e.convergence.materials)
            os << "<a href=\"convergence/" << esc(m) << "_history.csv\">" << esc(m)
               << "_history.csv</a>, <a href=\"convergence/" << esc(m) << "_snapshots.csv\">"
               << esc(m) << "_snapshots.csv</a> ";
        os << "</p>\n";
        figures(os, c.plots, "convergence");
    }

    if (c.engine_files) engine_report(r, *c.engine_files, c.plots, os);

    if (!c.studies.empty()) {
        os << "<h2 id=\"kernels\">Kernel studies</h2>\n";
        for (const auto& so : c.studies) study_section(os, so, c.plots);
    }
    bool viewers = false;
    for (const ReportContent::Study& s : c.sections)
        viewers = study_section_html(os, s.section, s.plots) || viewers;
    if (viewers) os << flip_viewer_script();

    os << "<h2 id=\"metrics\">Metrics</h2>\n<p>What <code>ssslab check</code> compares with the "
          "baselines in <code>results/baselines/</code>: stochastic metrics by z-score with "
          "their standard errors, deterministic ones with the stated relative tolerance. "
          "R<sub>d</sub> within k MFP is the reflectance through the bins inside k mean free "
          "paths; its standard error is the quadrature sum over the bins, an upper bound. "
          "One table per quantity, a row per material (or scene, or study entry) and a column "
          "per channel; hover a value for the metric's name. Table: <a href=\"metrics.csv\">"
          "metrics.csv</a>.</p>\n";
    metrics_tables(os, r.metrics);

    provenance_section(os, r);
    os << "<h2 id=\"configuration\">Resolved configuration</h2>\n<p>Every default filled in "
          "(<a href=\"experiment.toml\">experiment.toml</a>).</p>\n<pre>"
       << esc(e.doc->resolved_toml()) << "</pre>\n";
    os << kImageCheck << "</body>\n</html>\n";
    const std::string body = os.str();
    return head + contents(body) + body;
}

}  // namespace ssslab::runner
