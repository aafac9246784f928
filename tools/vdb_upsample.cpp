// vdb_upsample: makes a large volume from a small one (issue 24), to have big
// assets for memory and speed measurements.
//
// Usage: vdb_upsample IN.vdb OUT.vdb --factor N [--grid density] [--detail AMP]
//        [--seed S] [--threshold T] [--compression none|zip|blosc] [--threads K]
//
// The output float grid has N times the resolution per axis over the same
// world region: output index point q samples the source (trilinear,
// tools::BoxSampler) at source index point (q + 0.5) / N - 0.5, so voxel
// centres align and the world bounds match. With --detail the value is
// multiplied by max(0, 1 + AMP * noise(q)), a fractal hash value noise of the
// output index. Values <= T (default 0) stay inactive, so the grid stays sparse.
//
// Leaf by leaf: the output leaves that can hold a value are those near the
// source's leaves and tiles (dilated by one source voxel); TBB threads fill
// them into their own trees, merged at the end. Every value is a pure function
// of q, so the grid is the same for any thread count (io::File still stamps a
// random UUID into each file's header). OUT is written under a temporary name
// and renamed, so it is never left partial.

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/Interpolation.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_reduce.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using openvdb::Index;
using LeafT = FloatTree::LeafNodeType;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string num(double v)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

struct Options {
    std::string in, out, grid = "density", compression = "blosc";
    int factor = 0;
    double detail = 0.0, threshold = 0.0;
    std::uint64_t seed = 1;
    int threads = 0; // 0: TBB's default
};

// The source index coordinate that output index coordinate q samples (per axis).
inline double sourcePos(int q, int n) { return (static_cast<double>(q) + 0.5) / n - 0.5; }

// ---------------------------------------------------------------------------
// Detail: value noise on a hashed integer lattice, a few octaves.

inline double latticeValue(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed)
{
    std::uint64_t h = seed + 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(x) * 0xC2B2AE3D27D4EB4Full;
    h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull;
    h ^= static_cast<std::uint64_t>(y) * 0x165667B19E3779F9ull;
    h = (h ^ (h >> 32)) * 0x94D049BB133111EBull;
    h ^= static_cast<std::uint64_t>(z) * 0xD6E8FEB86659FD93ull;
    h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
    return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0; // [-1, 1)
}

// Up to four octaves of value noise (lattice periods 4N, 2N, N, N/2 output
// voxels, none under 2), each smoothly interpolated; in [-1, 1].
struct Detail {
    std::vector<double> periods;
    std::uint64_t seed;

    Detail(int n, std::uint64_t s) : seed(s)
    {
        for (double p = 4.0 * n; periods.size() < 4 && p >= 2.0; p *= 0.5) periods.push_back(p);
    }

    // The noise at the 8^3 voxels of the leaf at `origin`, by leaf offset.
    void leaf(const Coord& origin, double (&out)[LeafT::SIZE]) const
    {
        std::fill(out, out + LeafT::SIZE, 0.0);
        double norm = 0.0, amp = 1.0;
        for (size_t o = 0; o < periods.size(); ++o, amp *= 0.5) {
            norm += amp;
            // Per axis: lattice cell (from the first) and smoothed fraction.
            const double f = 1.0 / periods[o];
            std::int64_t base[3];
            int cell[3][8];
            double u[3][8];
            for (int a = 0; a < 3; ++a)
                for (int t = 0; t < 8; ++t) {
                    const double x = (origin[a] + t) * f, fl = std::floor(x), w = x - fl;
                    if (t == 0) base[a] = static_cast<std::int64_t>(fl);
                    cell[a][t] = static_cast<int>(static_cast<std::int64_t>(fl) - base[a]);
                    u[a][t] = w * w * (3.0 - 2.0 * w);
                }
            // The lattice values the leaf reads (periods >= 2: at most 6 per axis).
            double lat[6][6][6];
            for (int i = 0; i <= cell[0][7] + 1; ++i)
                for (int j = 0; j <= cell[1][7] + 1; ++j)
                    for (int k = 0; k <= cell[2][7] + 1; ++k)
                        lat[i][j][k] = latticeValue(base[0] + i, base[1] + j, base[2] + k, seed * 0x100000001B3ull + o);
            auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
            for (int x = 0; x < 8; ++x)
                for (int y = 0; y < 8; ++y)
                    for (int z = 0; z < 8; ++z) {
                        const int i = cell[0][x], j = cell[1][y], k = cell[2][z];
                        const double w = u[2][z];
                        const double n = lerp(lerp(lerp(lat[i][j][k], lat[i][j][k + 1], w),
                                                   lerp(lat[i][j + 1][k], lat[i][j + 1][k + 1], w), u[1][y]),
                                              lerp(lerp(lat[i + 1][j][k], lat[i + 1][j][k + 1], w),
                                                   lerp(lat[i + 1][j + 1][k], lat[i + 1][j + 1][k + 1], w), u[1][y]),
                                              u[0][x]);
                        out[LeafT::coordToOffset(Coord(x, y, z))] += amp * n;
                    }
        }
        for (double& v : out) v /= norm;
    }
};

// ---------------------------------------------------------------------------
// The output leaves to fill

// Origins of the output leaves that can hold a value above the threshold:
// those over the source's leaves and tiles (active, or of another value than
// the background), dilated by one source voxel. Sorted, unique.
std::vector<Coord> outputLeafOrigins(const FloatTree& src, int n)
{
    std::vector<CoordBBox> boxes;
    for (auto it = src.cbeginLeaf(); it; ++it) boxes.push_back(it->getNodeBoundingBox());
    auto tiles = src.cbeginValueAll();
    tiles.setMaxDepth(FloatTree::ValueAllCIter::LEAF_DEPTH - 1);
    for (; tiles; ++tiles)
        if (tiles.isValueOn() || !openvdb::math::isExactlyEqual(*tiles, src.background()))
            boxes.push_back(tiles.getBoundingBox());

    // Source voxel c is a corner of the cells floor(p) = c - 1 and c; output
    // voxel q lies in cell i when q is in [n i + n/2, n i + n + n/2 - 1].
    std::vector<Coord> origins;
    double count = 0;
    for (CoordBBox& b : boxes) {
        for (int a = 0; a < 3; ++a) {
            const std::int64_t lo = std::int64_t(n) * (b.min()[a] - 1) + n / 2;
            const std::int64_t hi = std::int64_t(n) * b.max()[a] + n + n / 2 - 1;
            if (lo < INT32_MIN + 8 || hi > INT32_MAX - 8)
                throw std::runtime_error("the output index range overflows 32-bit coordinates");
            b.min()[a] = static_cast<int>(lo) & ~7;
            b.max()[a] = static_cast<int>(hi) & ~7;
        }
        count += (b.dim().asVec3d() / 8.0 + openvdb::Vec3d(1.0)).product();
        if (count > 1e9) throw std::runtime_error("the output would have more than a billion leaves");
        for (int x = b.min().x(); x <= b.max().x(); x += 8)
            for (int y = b.min().y(); y <= b.max().y(); y += 8)
                for (int z = b.min().z(); z <= b.max().z(); z += 8) origins.emplace_back(x, y, z);
    }
    std::sort(origins.begin(), origins.end());
    origins.erase(std::unique(origins.begin(), origins.end()), origins.end());
    origins.shrink_to_fit();
    return origins;
}

// ---------------------------------------------------------------------------
// Filling the leaves

struct Job {
    const FloatTree& src;
    int n;
    float threshold;
    double detailAmp;
    Detail detail;
    const std::vector<Coord>& origins;
    Clock::time_point start;
    std::atomic<size_t> done{0};
    std::mutex printMutex;

    Job(const FloatTree& s, int factor, const Options& o, const std::vector<Coord>& leaves)
        : src(s), n(factor), threshold(static_cast<float>(o.threshold)), detailAmp(o.detail),
          detail(factor, o.seed), origins(leaves), start(Clock::now())
    {
    }

    // Counts `k` more leaves done; prints each 5 %.
    void progress(size_t k)
    {
        const size_t before = done.fetch_add(k), total = origins.size();
        if (before * 20 / total == (before + k) * 20 / total) return;
        std::lock_guard<std::mutex> lock(printMutex);
        std::printf("  %3zu%% of %zu candidate leaves, %.1f s\n", (before + k) * 100 / total, total, since(start));
        std::fflush(stdout);
    }
};

// Fills the output leaf at `origin` into `tree`: a leaf, or an active tile
// when all its voxels are active and equal; nothing when none is active.
template <typename Accessor>
void fillLeaf(const Coord& origin, Accessor& acc, const Job& job, FloatTree& tree)
{
    // Per axis: the source cells (floor of the sample position) and weights.
    int cell[3][8], lo[3];
    double weight[3][8];
    for (int a = 0; a < 3; ++a) {
        for (int t = 0; t < 8; ++t) {
            const double p = sourcePos(origin[a] + t, job.n);
            cell[a][t] = openvdb::math::Floor(p);
            weight[a][t] = p - cell[a][t];
        }
        lo[a] = cell[a][0];
        for (int t = 0; t < 8; ++t) cell[a][t] -= lo[a];
    }
    // The source values they read (at most 9^3, at n = 1).
    const int dx = cell[0][7] + 2, dy = cell[1][7] + 2, dz = cell[2][7] + 2;
    float block[9][9][9];
    float maxValue = -std::numeric_limits<float>::infinity();
    for (int i = 0; i < dx; ++i)
        for (int j = 0; j < dy; ++j)
            for (int k = 0; k < dz; ++k) {
                block[i][j][k] = acc.getValue(Coord(lo[0] + i, lo[1] + j, lo[2] + k));
                maxValue = std::max(maxValue, block[i][j][k]);
            }
    // Trilinear interpolation of values <= 0 stays <= 0, and so does detail.
    if (maxValue <= 0.0f && job.threshold >= 0.0f) return;

    auto leaf = std::make_unique<LeafT>(origin, tree.background(), false);
    double noise[LeafT::SIZE];
    if (job.detailAmp != 0.0) job.detail.leaf(origin, noise);
    float data[2][2][2];
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z) {
                const int i = cell[0][x], j = cell[1][y], k = cell[2][z];
                for (int a = 0; a < 2; ++a)
                    for (int b = 0; b < 2; ++b)
                        for (int c = 0; c < 2; ++c) data[a][b][c] = block[i + a][j + b][k + c];
                // As BoxSampler::sample(acc, p): same corners, same weights.
                const openvdb::Vec3R uvw(weight[0][x], weight[1][y], weight[2][z]);
                float v = openvdb::tools::BoxSampler::trilinearInterpolation(data, uvw);
                const Index offset = LeafT::coordToOffset(Coord(x, y, z));
                if (job.detailAmp != 0.0)
                    v = static_cast<float>(v * std::max(0.0, 1.0 + job.detailAmp * noise[offset]));
                if (v > job.threshold) leaf->setValueOn(offset, v);
            }
    if (leaf->isEmpty()) return;
    const float first = leaf->getFirstValue();
    const auto& buf = leaf->buffer();
    if (leaf->isDense() && std::all_of(buf.data(), buf.data() + LeafT::SIZE, [&](float v) { return v == first; }))
        tree.addTile(1, origin, first, true);
    else
        tree.addLeaf(leaf.release());
}

// tbb::parallel_reduce body: fills its ranges into its own tree; join merges.
struct Builder {
    Job& job;
    std::unique_ptr<FloatTree> tree;

    explicit Builder(Job& j) : job(j), tree(new FloatTree(j.src.background())) {}
    Builder(Builder& other, tbb::split) : Builder(other.job) {}

    void operator()(const tbb::blocked_range<size_t>& r)
    {
        openvdb::tree::ValueAccessor<const FloatTree> acc(job.src);
        for (size_t i = r.begin(); i != r.end(); ++i) fillLeaf(job.origins[i], acc, job, *tree);
        job.progress(r.size());
    }
    // The trees hold disjoint leaves and tiles: merging moves nodes, copies nothing.
    void join(Builder& other) { tree->merge(*other.tree, openvdb::MERGE_ACTIVE_STATES_AND_NODES); }
};

// ---------------------------------------------------------------------------
// Input and output

FloatGrid::Ptr readSource(const Options& o)
{
    if (!fs::exists(o.in)) throw std::runtime_error("cannot read " + o.in + ": no such file");
    openvdb::io::File file(o.in);
    try {
        file.open();
    } catch (const std::exception& e) {
        throw std::runtime_error("cannot read " + o.in + ": " + e.what());
    }
    if (!file.hasGrid(o.grid)) {
        std::string names;
        for (auto it = file.beginName(); it != file.endName(); ++it) names += (names.empty() ? "" : ", ") + *it;
        throw std::runtime_error(o.in + " has no grid named '" + o.grid + "' (it has: " +
                                 (names.empty() ? "none" : names) + ")");
    }
    openvdb::GridBase::Ptr base = file.readGrid(o.grid);
    file.close();
    auto grid = openvdb::gridPtrCast<FloatGrid>(base);
    if (!grid)
        throw std::runtime_error("grid '" + o.grid + "' in " + o.in + " holds " + base->valueType() +
                                 " values, not float");
    if (!grid->transform().isLinear())
        throw std::runtime_error("grid '" + o.grid + "' in " + o.in + " has a non-linear (" +
                                 grid->transform().mapType() + ") transform");
    return grid;
}

// The source transform with index point q mapped to source index (q + 0.5) / n - 0.5.
openvdb::math::Transform::Ptr outputTransform(const openvdb::math::Transform& src, int n)
{
    auto xform = src.copy();
    xform->preTranslate(openvdb::Vec3d(0.5 / n - 0.5));
    xform->preScale(1.0 / n);
    // The output point at source voxel (0,0,0) (a centre when n is odd) and a far corner.
    for (const openvdb::Vec3d& p : {openvdb::Vec3d(0.0), openvdb::Vec3d(-7.5, 100.5, 1000.5)}) {
        const openvdb::Vec3d q = (p + openvdb::Vec3d(0.5)) * n - openvdb::Vec3d(0.5);
        const openvdb::Vec3d ws = src.indexToWorld(p), wo = xform->indexToWorld(q);
        if ((ws - wo).length() > 1e-9 * (1.0 + ws.length()))
            throw std::logic_error("the output transform does not line up with the source");
    }
    return xform;
}

// Fails early when OUT's folder is missing or not writable.
void checkOutputFolder(const Options& o)
{
    const fs::path dir = fs::path(o.out).parent_path().empty() ? fs::path(".") : fs::path(o.out).parent_path();
    if (!fs::is_directory(dir)) throw std::runtime_error("cannot write " + o.out + ": no folder " + dir.string());
    if (::access(dir.c_str(), W_OK) != 0) throw std::runtime_error("cannot write " + o.out + ": folder not writable");
}

// Writes `grid` to OUT under a temporary name in the same folder, then renames it.
void writeOutput(const Options& o, const FloatGrid::Ptr& grid)
{
    std::uint32_t compression = openvdb::io::COMPRESS_ACTIVE_MASK;
    if (o.compression == "zip") compression |= openvdb::io::COMPRESS_ZIP;
    if (o.compression == "blosc") {
        if (!openvdb::io::Archive::hasBloscCompression())
            throw std::runtime_error("this OpenVDB build has no Blosc compression (use --compression zip)");
        compression |= openvdb::io::COMPRESS_BLOSC;
    }
    const fs::path out(o.out);
    const fs::path tmp = out.parent_path() / ("." + out.filename().string() + ".tmp-" + std::to_string(::getpid()));
    openvdb::MetaMap meta;
    meta.insertMeta("generator", openvdb::StringMetadata("vdb_upsample (vdbmarch): " +
                                                         fs::path(o.in).filename().string() + " x" +
                                                         std::to_string(o.factor)));
    try {
        openvdb::io::File file(tmp.string());
        file.setCompression(compression);
        file.write(openvdb::GridCPtrVec{grid}, meta);
        file.close();
        fs::rename(tmp, out);
    } catch (const std::exception& e) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        throw std::runtime_error("cannot write " + o.out + ": " + e.what());
    }
}

// ---------------------------------------------------------------------------

[[noreturn]] void usage(const std::string& why)
{
    std::fprintf(stderr,
                 "vdb_upsample: error: %s\n"
                 "Usage: vdb_upsample IN.vdb OUT.vdb --factor N [--grid density] [--detail AMP] [--seed S]\n"
                 "       [--threshold T] [--compression none|zip|blosc] [--threads K]\n",
                 why.c_str());
    std::exit(2);
}

// A whole number from `lo` to `hi`, or a usage error naming the option.
long long wholeNumber(const std::string& opt, const std::string& text, long long lo, long long hi)
{
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(text.c_str(), &end, 10);
    if (text.empty() || *end || errno || v < lo || v > hi)
        usage(opt + " takes a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) + " (got '" +
              text + "')");
    return v;
}

double realNumber(const std::string& opt, const std::string& text)
{
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end || !std::isfinite(v)) usage(opt + " takes a number (got '" + text + "')");
    return v;
}

Options parseArgs(int argc, char** argv)
{
    Options o;
    std::vector<std::string> files;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a.size() < 2 || a.compare(0, 2, "--") != 0) {
            files.push_back(a);
            continue;
        }
        if (i + 1 >= argc) usage(a + " needs a value");
        const std::string v = argv[++i];
        if (a == "--factor") o.factor = static_cast<int>(wholeNumber(a, v, 1, 32));
        else if (a == "--grid") o.grid = v;
        else if (a == "--detail") o.detail = realNumber(a, v);
        else if (a == "--seed") o.seed = static_cast<std::uint64_t>(wholeNumber(a, v, 0, INT64_MAX));
        else if (a == "--threshold") o.threshold = realNumber(a, v);
        else if (a == "--threads") o.threads = static_cast<int>(wholeNumber(a, v, 1, 1024));
        else if (a == "--compression") {
            if (v != "none" && v != "zip" && v != "blosc") usage("--compression takes none, zip or blosc");
            o.compression = v;
        } else
            usage("unknown option " + a);
    }
    if (files.size() != 2) usage("expected IN.vdb and OUT.vdb");
    if (o.factor == 0) usage("--factor N (1 to 32) is required");
    o.in = files[0];
    o.out = files[1];
    return o;
}

} // namespace

int main(int argc, char** argv)
{
    const Options o = parseArgs(argc, argv);
    std::optional<tbb::global_control> threads;
    if (o.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, o.threads);
    try {
        openvdb::initialize();
        checkOutputFolder(o);
        const auto t0 = Clock::now();
        const FloatGrid::Ptr src = readSource(o);
        const FloatTree& st = src->tree();
        std::printf("%s: grid '%s', %llu active voxels, %llu leaves, %llu active tiles, voxel size %g\n",
                    o.in.c_str(), o.grid.c_str(), static_cast<unsigned long long>(st.activeVoxelCount()),
                    static_cast<unsigned long long>(st.leafCount()),
                    static_cast<unsigned long long>(st.activeTileCount()), src->voxelSize().x());

        if (!(src->background() <= o.threshold))
            throw std::runtime_error("grid '" + o.grid + "' in " + o.in + ": its background " +
                                     num(src->background()) + " is above --threshold " + num(o.threshold) +
                                     " (all of space would be active)");
        const int n = o.factor;
        const std::vector<Coord> origins = outputLeafOrigins(st, n);
        std::printf("x%d: %zu candidate output leaves (%.1f s)\n", n, origins.size(), since(t0));
        std::fflush(stdout);
        Job job(st, n, o, origins);
        Builder builder(job);
        if (!origins.empty()) tbb::parallel_reduce(tbb::blocked_range<size_t>(0, origins.size(), 16), builder);

        FloatGrid::Ptr grid = FloatGrid::create(FloatTree::Ptr(builder.tree.release()));
        grid->setName(o.grid);
        grid->setTransform(outputTransform(src->transform(), n));
        grid->setGridClass(src->getGridClass());
        grid->setCreator("vdb_upsample (vdbmarch)");
        const double built = since(t0);
        const auto t1 = Clock::now();
        writeOutput(o, grid);
        const double written = since(t1);

        std::printf("%s: grid '%s' x%d%s\n", o.out.c_str(), o.grid.c_str(), n,
                    o.detail != 0.0 ? (", detail " + num(o.detail) + " seed " +
                                       std::to_string(o.seed)).c_str() : "");
        std::printf("  active voxels  %llu\n", static_cast<unsigned long long>(grid->activeVoxelCount()));
        std::printf("  leaves         %llu (active tiles %llu)\n",
                    static_cast<unsigned long long>(grid->tree().leafCount()),
                    static_cast<unsigned long long>(grid->tree().activeTileCount()));
        std::printf("  memUsage       %llu bytes\n", static_cast<unsigned long long>(grid->memUsage()));
        std::printf("  file           %llu bytes (%s)\n",
                    static_cast<unsigned long long>(fs::file_size(o.out)), o.compression.c_str());
        std::printf("  seconds        %.2f (read and build %.2f, write %.2f)\n", since(t0), built, written);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdb_upsample: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
