// exrstat: per-channel statistics of RGB EXR images, for comparing pbrt-v4 and vdbmarch renders
// without Python image modules. Build (Debian 12, libopenexr-dev):
//   g++ -O2 -std=c++17 -I/usr/include/OpenEXR -I/usr/include/Imath exrstat.cpp -o exrstat \
//       -lOpenEXR-3_1 -lIex-3_1 -lImath-3_1
// Usage:
//   exrstat mean A.exr [B.exr]
//       per-channel mean of A (or of (A+B)/2) and, with two independent renders, the standard
//       error of that mean from their pixel differences: se_c = sqrt(sum_p (a-b)^2) / (2 N).
//   exrstat cmp T1.exr T2.exr R1.exr R2.exr
//       test T = (T1+T2)/2 against reference R = (R1+R2)/2: per-channel means, their ratio T/R
//       with its standard error, RMSE(T-R) over all pixels and channels relative to R's mean,
//       the part of it the noise explains (the halves' differences), the rest ("excess"), and the
//       RMSE with T mirrored left-right (a handedness check).
// Only the R, G, B channels (any pixel type, read as float) of the default layer are read.
#include <ImfArray.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

struct Img {
    int w = 0, h = 0;
    std::vector<float> px[3];
};

static Img load(const char* path) {
    Imf::InputFile f(path);
    auto dw = f.header().dataWindow();
    Img im;
    im.w = dw.max.x - dw.min.x + 1;
    im.h = dw.max.y - dw.min.y + 1;
    Imf::FrameBuffer fb;
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        if (!f.header().channels().findChannel(names[c])) {
            std::fprintf(stderr, "exrstat: %s has no channel %s\n", path, names[c]);
            std::exit(2);
        }
        im.px[c].assign(size_t(im.w) * im.h, 0.f);
        char* base = (char*)(im.px[c].data() - dw.min.x - size_t(dw.min.y) * im.w);
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * im.w));
    }
    f.setFrameBuffer(fb);
    f.readPixels(dw.min.y, dw.max.y);
    return im;
}

static void same(const Img& a, const Img& b, const char* n) {
    if (a.w != b.w || a.h != b.h) {
        std::fprintf(stderr, "exrstat: %s: size %dx%d differs from %dx%d\n", n, b.w, b.h, a.w, a.h);
        std::exit(2);
    }
}

int main(int argc, char** argv) {
    if (argc >= 3 && !std::strcmp(argv[1], "mean")) {
        Img a = load(argv[2]);
        bool two = argc >= 4;
        Img b = two ? load(argv[3]) : Img();
        if (two) same(a, b, argv[3]);
        double n = double(a.w) * a.h;
        std::printf("size %d %d\n", a.w, a.h);
        for (int c = 0; c < 3; ++c) {
            double s = 0, d2 = 0;
            for (size_t i = 0; i < a.px[c].size(); ++i) {
                double va = a.px[c][i], vb = two ? b.px[c][i] : va;
                s += 0.5 * (va + vb);
                d2 += (va - vb) * (va - vb);
            }
            std::printf("mean_%c %.7g se %.3g\n", "RGB"[c], s / n, two ? std::sqrt(d2) / (2 * n) : 0.0);
        }
        return 0;
    }
    if (argc == 6 && !std::strcmp(argv[1], "cmp")) {
        Img t1 = load(argv[2]), t2 = load(argv[3]), r1 = load(argv[4]), r2 = load(argv[5]);
        same(t1, t2, argv[3]); same(t1, r1, argv[4]); same(t1, r2, argv[5]);
        int w = t1.w, h = t1.h;
        double n = double(w) * h;
        double sq = 0, sqm = 0, noise = 0, meanAll = 0;
        for (int c = 0; c < 3; ++c) {
            double st = 0, sr = 0, dt = 0, dr = 0;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    size_t i = size_t(y) * w + x, im = size_t(y) * w + (w - 1 - x);
                    double t = 0.5 * (t1.px[c][i] + t2.px[c][i]);
                    double tm = 0.5 * (t1.px[c][im] + t2.px[c][im]);
                    double r = 0.5 * (r1.px[c][i] + r2.px[c][i]);
                    double a = t1.px[c][i] - t2.px[c][i], b = r1.px[c][i] - r2.px[c][i];
                    st += t; sr += r; dt += a * a; dr += b * b;
                    sq += (t - r) * (t - r);
                    sqm += (tm - r) * (tm - r);
                    noise += 0.25 * (a * a + b * b);
                }
            double mt = st / n, mr = sr / n;
            double set = std::sqrt(dt) / (2 * n), ser = std::sqrt(dr) / (2 * n);
            double ratio = mt / mr;
            double seRatio = ratio * std::sqrt((set / mt) * (set / mt) + (ser / mr) * (ser / mr));
            std::printf("%c mean_test %.6g (se %.2g) mean_ref %.6g (se %.2g) ratio %.5f +- %.5f\n",
                        "RGB"[c], mt, set, mr, ser, ratio, seRatio);
            meanAll += mr / 3;
        }
        double N = 3 * n;
        double rmse = std::sqrt(sq / N), rmseM = std::sqrt(sqm / N), rn = std::sqrt(noise / N);
        double excess = rmse * rmse > rn * rn ? std::sqrt(rmse * rmse - rn * rn) : 0.0;
        std::printf("rmse_over_mean %.5f noise_part %.5f excess %.5f mirrored_rmse_over_mean %.5f\n",
                    rmse / meanAll, rn / meanAll, excess / meanAll, rmseM / meanAll);
        return 0;
    }
    std::fprintf(stderr, "usage: exrstat mean A.exr [B.exr] | exrstat cmp T1 T2 R1 R2\n");
    return 2;
}
