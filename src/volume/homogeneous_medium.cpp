#include "core/error.h"
#include "volume/medium.h"

namespace vdbmarch {

namespace {

class HomogeneousQuery final : public MediumQuery {
public:
    HomogeneousQuery(bool bounded, const BBox& b) : mBounded(bounded), mBounds(b) {}
    float density(const Vec3& p) override { return (!mBounded || mBounds.contains(p)) ? 1.f : 0.f; }
    float emission(const Vec3&) override { return 0; }
    void activeIntervals(const Ray& r, float tMin, float tMax, std::vector<Interval>& out) override {
        if (!mBounded) {
            out.push_back({tMin, tMax});
            return;
        }
        float t0 = tMin, t1 = tMax;
        if (mBounds.intersect(r, t0, t1) && t1 > t0) out.push_back({t0, t1});
    }

    void forEachDensityBound(const Ray& r, float tMin, float tMax,
                         const std::function<bool(const DensityBound&)>& visit) override {
        float t0 = tMin, t1 = tMax;
        if (!mBounded || (mBounds.intersect(r, t0, t1) && t1 > t0)) visit({t0, t1, 1.f, 1.f});
    }
    bool densityIntegral(const Ray& r, float tMin, float tMax, float& integral) override {
        integral = 0;
        float t0 = tMin, t1 = tMax;
        if (!mBounded || (mBounds.intersect(r, t0, t1) && t1 > t0)) integral = t1 - t0;
        return true;
    }

private:
    bool mBounded;
    BBox mBounds;
};

class HomogeneousMedium final : public Medium {
public:
    explicit HomogeneousMedium(const MediumDesc& d) : mBounded(d.hasBounds), mBounds(d.bounds) {
        name = d.name;
        sigma_a = d.sigma_a;
        sigma_s = d.sigma_s;
        g = d.g;
    }
    std::unique_ptr<MediumQuery> makeQuery() const override {
        return std::make_unique<HomogeneousQuery>(mBounded, mBounds);
    }
    BBox worldBounds() const override {
        if (mBounded) return mBounds;
        BBox b;
        b.lo = Vec3(-Infinity);
        b.hi = Vec3(Infinity);
        return b;
    }
    float maxDensity() const override { return 1; }
    void activeBoxes(std::vector<BBox>& out) const override {
        if (mBounded) out.push_back(mBounds);
    }

private:
    bool mBounded;
    BBox mBounds;
};

}  // namespace

std::unique_ptr<Medium> makeHomogeneousMedium(const MediumDesc& desc) {
    return std::make_unique<HomogeneousMedium>(desc);
}

}  // namespace vdbmarch
