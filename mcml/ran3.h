// The random number generator of MCML 1.2.2, for the compatibility mode.
//
// Knuth's subtractive generator as in Numerical Recipes' ran3 (returning a float, so 1.0 can come
// out), seeded as MCML's RandomNum() does: one call with the (negative) seed idum, its value
// discarded, then idum = 1 for every later call. The state lives in the object instead of C
// statics; one object spans all runs of an .mci file, as the original process does.
#pragma once

namespace ssslab::mcml {

class Ran3 {
  public:
    /// `idum` as the original computes it: -(int)time(NULL) % (1 << 15) (e.g. -24832).
    explicit Ran3(int idum) : idum_(idum) {
        (void)next();  // RandomNum()'s first call, discarded
        idum_ = 1;
    }

    /// MCML's RandomNum(): (double)ran3(&idum).
    double uniform() { return static_cast<double>(next()); }

  private:
    static constexpr long kMBig = 1000000000;
    static constexpr long kMSeed = 161803398;
    static constexpr long kMZ = 0;
    static constexpr double kFac = 1.0e-9;

    float next() {
        long mj, mk;
        int i, ii, k;
        if (idum_ < 0 || iff_ == 0) {
            iff_ = 1;
            mj = kMSeed - (idum_ < 0 ? -idum_ : idum_);
            mj %= kMBig;
            ma_[55] = mj;
            mk = 1;
            for (i = 1; i <= 54; i++) {
                ii = (21 * i) % 55;
                ma_[ii] = mk;
                mk = mj - mk;
                if (mk < kMZ) mk += kMBig;
                mj = ma_[ii];
            }
            for (k = 1; k <= 4; k++)
                for (i = 1; i <= 55; i++) {
                    ma_[i] -= ma_[1 + (i + 30) % 55];
                    if (ma_[i] < kMZ) ma_[i] += kMBig;
                }
            inext_ = 0;
            inextp_ = 31;
            idum_ = 1;
        }
        if (++inext_ == 56) inext_ = 1;
        if (++inextp_ == 56) inextp_ = 1;
        mj = ma_[inext_] - ma_[inextp_];
        if (mj < kMZ) mj += kMBig;
        ma_[inext_] = mj;
        return static_cast<float>(static_cast<double>(mj) * kFac);
    }

    int idum_;
    int inext_ = 0, inextp_ = 0;
    long ma_[56] = {};
    int iff_ = 0;
};

}  // namespace ssslab::mcml
