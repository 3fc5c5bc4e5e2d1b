#include "mcml/tally.h"

#include <cmath>

namespace ssslab::mcml {

TallyLayout TallyLayout::make(const RunSpec& run, TallyMode mode) {
    TallyLayout l;
    l.mode = mode;
    l.nr = run.grid.nr;
    l.nz = run.grid.nz;
    l.na = run.grid.na;
    l.nl = run.num_layers();
    const size_t nr = static_cast<size_t>(l.nr), nz = static_cast<size_t>(l.nz),
                 na = static_cast<size_t>(l.na), nl2 = static_cast<size_t>(l.nl) + 2;
    size_t o = 0;
    if (mode == TallyMode::kFull) {
        l.rd_ra = o, o += nr * na;
        l.tt_ra = o, o += nr * na;
        l.a_rz = o, o += nr * nz;
        l.primary_size = o;
        l.rd_r = o, o += nr;
        l.rd_a = o, o += na;
        l.tt_r = o, o += nr;
        l.tt_a = o, o += na;
        l.a_z = o, o += nz;
        l.a_l = o, o += nl2;
    } else {
        l.rd_r = o, o += nr + 1;  // [nr] is the overflow bin
        l.tt_r = o, o += nr + 1;
        l.a_layer = o, o += nl2;
        l.primary_size = o;
    }
    l.rd = o++;
    l.a = o++;
    l.tt = o++;
    l.energy = o++;
    l.size = o;
    return l;
}

namespace {

// MCML's IzToLayer(): the layer holding the centre of depth bin iz.
int iz_to_layer(int iz, const RunSpec& run) {
    int i = 1;
    const int nl = run.num_layers();
    const double dz = run.grid.dz;
    while ((iz + 0.5) * dz >= run.layers[static_cast<size_t>(i)].z1 && i < nl) i++;
    return i;
}

// out[j] = sum over i = 0, 1, ..., rows - 1 of m[i * cols + j], each sum in the order of i.
void sum_columns(const double* __restrict m, int rows, int cols, double* __restrict out) {
    for (int j = 0; j < cols; ++j) out[j] = 0.0;
    for (int i = 0; i < rows; ++i) {
        const double* __restrict row = m + static_cast<size_t>(i) * static_cast<size_t>(cols);
        for (int j = 0; j < cols; ++j) out[j] += row[j];
    }
}

}  // namespace

void reduce(const RunSpec& run, double* v, const TallyLayout& L) {
    const int nr = L.nr, na = L.na, nz = L.nz;
    if (L.mode == TallyMode::kProfile) {
        double rd = 0.0, tt = 0.0, a = 0.0;
        for (int ir = 0; ir <= nr; ++ir) rd += v[L.rd_r + ir], tt += v[L.tt_r + ir];
        for (int il = 0; il < L.nl + 2; ++il) a += v[L.a_layer + il];
        v[L.rd] = rd, v[L.tt] = tt, v[L.a] = a, v[L.energy] = rd + a + tt;
        return;
    }
    // Sum2DRd / Sum2DTt. The column sums run over the rows in the original's order (ir = 0, 1,
    // ...), each into its own accumulator, so the sums are the original's bit for bit; walking
    // the rows contiguously rather than the columns with a stride of a row keeps this per-batch
    // pass at memory speed.
    auto sum2d = [&](size_t ra, size_t r, size_t a, size_t total) {
        double sum;
        for (int ir = 0; ir < nr; ir++) {
            sum = 0.0;
            for (int ia = 0; ia < na; ia++) sum += v[ra + static_cast<size_t>(ir * na + ia)];
            v[r + ir] = sum;
        }
        sum_columns(v + ra, nr, na, v + a);
        sum = 0.0;
        for (int ir = 0; ir < nr; ir++) sum += v[r + ir];
        v[total] = sum;
    };
    sum2d(L.rd_ra, L.rd_r, L.rd_a, L.rd);
    // Sum2DA
    {
        sum_columns(v + L.a_rz, nr, nz, v + L.a_z);
        for (int il = 0; il < L.nl + 2; ++il) v[L.a_l + il] = 0.0;
        double sum = 0.0;
        for (int iz = 0; iz < nz; iz++) {
            sum += v[L.a_z + iz];
            v[L.a_l + iz_to_layer(iz, run)] += v[L.a_z + iz];
        }
        v[L.a] = sum;
    }
    sum2d(L.tt_ra, L.tt_r, L.tt_a, L.tt);
    v[L.energy] = v[L.rd] + v[L.a] + v[L.tt];
}

McoResult scale_full(const RunSpec& run, const std::vector<double>& t, const TallyLayout& L,
                     double num_photons, double PI, double rsp) {
    const int nr = L.nr, na = L.na, nz = L.nz, nl = L.nl;
    const double dr = run.grid.dr, dz = run.grid.dz;
    const double da = 0.5 * PI / na;  // ReadNzNrNa()
    McoResult o;
    o.rsp = rsp;
    auto copy = [&](size_t off, size_t n) {
        return std::vector<double>(t.begin() + static_cast<std::ptrdiff_t>(off),
                                   t.begin() + static_cast<std::ptrdiff_t>(off + n));
    };
    o.rd_ra = copy(L.rd_ra, static_cast<size_t>(nr) * na);
    o.tt_ra = copy(L.tt_ra, static_cast<size_t>(nr) * na);
    o.a_rz = copy(L.a_rz, static_cast<size_t>(nr) * nz);
    o.rd_r = copy(L.rd_r, static_cast<size_t>(nr));
    o.tt_r = copy(L.tt_r, static_cast<size_t>(nr));
    o.rd_a = copy(L.rd_a, static_cast<size_t>(na));
    o.tt_a = copy(L.tt_a, static_cast<size_t>(na));
    o.a_z = copy(L.a_z, static_cast<size_t>(nz));
    o.a_l = copy(L.a_l, static_cast<size_t>(nl) + 2);
    o.rd = t[L.rd];
    o.a = t[L.a];
    o.tt = t[L.tt];

    // ScaleRdTt()
    double scale1, scale2;
    scale1 = 4.0 * PI * PI * dr * std::sin(da / 2) * dr * num_photons;
    for (int ir = 0; ir < nr; ir++)
        for (int ia = 0; ia < na; ia++) {
            scale2 = 1.0 / ((ir + 0.5) * std::sin(2.0 * (ia + 0.5) * da) * scale1);
            o.rd_ra[static_cast<size_t>(ir * na + ia)] *= scale2;
            o.tt_ra[static_cast<size_t>(ir * na + ia)] *= scale2;
        }
    scale1 = 2.0 * PI * dr * dr * num_photons;
    for (int ir = 0; ir < nr; ir++) {
        scale2 = 1.0 / ((ir + 0.5) * scale1);
        o.rd_r[static_cast<size_t>(ir)] *= scale2;
        o.tt_r[static_cast<size_t>(ir)] *= scale2;
    }
    scale1 = 2.0 * PI * da * num_photons;
    for (int ia = 0; ia < na; ia++) {
        scale2 = 1.0 / (std::sin((ia + 0.5) * da) * scale1);
        o.rd_a[static_cast<size_t>(ia)] *= scale2;
        o.tt_a[static_cast<size_t>(ia)] *= scale2;
    }
    scale2 = 1.0 / num_photons;
    o.rd *= scale2;
    o.tt *= scale2;

    // ScaleA()
    scale1 = 2.0 * PI * dr * dr * dz * num_photons;
    for (int iz = 0; iz < nz; iz++)
        for (int ir = 0; ir < nr; ir++)
            o.a_rz[static_cast<size_t>(ir * nz + iz)] /= (ir + 0.5) * scale1;
    scale1 = 1.0 / (dz * num_photons);
    for (int iz = 0; iz < nz; iz++) o.a_z[static_cast<size_t>(iz)] *= scale1;
    scale1 = 1.0 / num_photons;
    for (int il = 0; il <= nl + 1; il++) o.a_l[static_cast<size_t>(il)] *= scale1;
    o.a *= scale1;
    return o;
}

}  // namespace ssslab::mcml
