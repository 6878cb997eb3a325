// SphereRender: shading a sphere with a compiled kernel (see SphereRender.h).
//
// The work is organized for the batched kernel: each image row becomes one
// batch of lanes (every covered pixel contributes 1 light lane + N sky
// lanes, with the estimator's weight kept beside each lane), the kernel
// evaluates the whole row at once, and the weighted values are summed back
// into the pixels. Rows are handed out to the threads one at a time.
#include "SphereRender.h"

#include "ImageFiles.h"

#include "Interpreter.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <thread>

namespace facet::preview {

namespace {

constexpr double kPi = std::numbers::pi;
// The sphere's diameter as a fraction of the image: a margin for the
// antialiased silhouette.
constexpr double kSphereFraction = 0.9;
// Shading stops this close to the silhouette (n.v >= ~0.03): the outermost
// ring of pixels is partly covered and is shaded at its inner edge, instead
// of at a point where the camera's ray only grazes the surface.
constexpr double kMaxDiskRadius = 0.9995;

struct Vec {
    double x = 0, y = 0, z = 0;
};
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec operator*(double s, Vec a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec cross(Vec a, Vec b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec normalize(Vec a) { return (1 / std::sqrt(dot(a, a))) * a; }

Vec sphericalDirection(double thetaDeg, double phiDeg) {
    double t = thetaDeg * kPi / 180, p = phiDeg * kPi / 180;
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

const Vec kWorldUp{0, 1, 0};

// The orthographic camera: `view` points towards it, `right` and `up` span
// the image plane (up as close to world +Y as the view allows).
struct Camera {
    Vec view, right, up;
    int size = 0;
    explicit Camera(const SphereScene& s) : view(sphericalDirection(s.viewThetaDeg, s.viewPhiDeg)), size(s.size) {
        Vec r = cross(kWorldUp, view);
        if (dot(r, r) < 1e-12) r = cross(Vec{0, 0, -1}, view);  // looking straight down or up
        right = normalize(r);
        up = cross(view, right);
    }
    double radiusPixels() const { return kSphereFraction * size / 2; }
    // Image-plane coordinates in sphere radii of pixel centre (x, y).
    double diskX(int x) const { return ((x + 0.5) / size * 2 - 1) / kSphereFraction; }
    double diskY(int y) const { return (1 - (y + 0.5) / size * 2) / kSphereFraction; }
};

std::array<float, 3> skyRadiance(const SphereScene& scene, Vec d) {
    double s = scene.skyRadiance;
    switch (scene.sky) {
        case SkyModel::None: return {0, 0, 0};
        case SkyModel::Constant: return {float(s), float(s), float(s)};
        case SkyModel::Gradient: {
            // A clear-sky look: pale at the horizon, deeper blue at the
            // zenith, a dim warm ground below (the horizon is a step, as in
            // an outdoor scene).
            constexpr double horizon[3] = {0.85, 0.90, 1.00}, zenith[3] = {0.25, 0.45, 0.95},
                             ground[3] = {0.30, 0.27, 0.24};
            std::array<float, 3> out;
            double t = std::sqrt(std::max(0.0, d.y));
            for (int c = 0; c < 3; ++c)
                out[c] = float(s * (d.y >= 0 ? horizon[c] + (zenith[c] - horizon[c]) * t : ground[c]));
            return out;
        }
    }
    return {0, 0, 0};
}

// The GGX roughness the sky samples follow: the material's own at its
// default inputs where its NDF has one (Blinn-Phong through the matched
// exponent), clamped to [1e-3, 1]. Any choice keeps the estimate unbiased.
std::array<double, 2> samplingRoughness(const Kernel& kernel) {
    Interpreter<double> interp(kernel.material(), kernel.energyTable());
    ResolvedMaterial<double> r = interp.resolve(nullptr);
    double ax = 1, ay = 1;
    if (r.valid) {
        std::array<double, 2> alphas = r.ndf->equivalentAlphas(r.ndfArgs);
        ax = alphas[0], ay = alphas[1];
    }
    auto clampAlpha = [](double a) { return std::isfinite(a) ? std::clamp(a, 1e-3, 1.0) : 1.0; };
    return {clampAlpha(ax), clampAlpha(ay)};
}

double radicalInverse2(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i * 0x1p-32;
}

uint64_t splitMix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// A 2D Hammersley point set, stored as u and the unit vector of angle 2 pi v
// so that rotating it per pixel costs a complex multiplication.
struct PointSet {
    std::vector<double> u, cosV, sinV;
    explicit PointSet(int n) {
        for (int i = 0; i < n; ++i) {
            u.push_back((i + 0.5) / n);
            double v = 2 * kPi * radicalInverse2(uint32_t(i));
            cosV.push_back(std::cos(v));
            sinV.push_back(std::sin(v));
        }
    }
    int size() const { return int(u.size()); }
    // Point i rotated by (du, angle with cos/sin cr, sr), mapped to the
    // cosine-weighted hemisphere.
    Vec cosineDirection(int i, double du, double cr, double sr) const {
        double uu = u[i] + du;
        uu -= std::floor(uu);
        double r = std::sqrt(uu);
        double c = cosV[i] * cr - sinV[i] * sr, s = sinV[i] * cr + cosV[i] * sr;
        return {r * c, r * s, std::sqrt(std::max(0.0, 1 - uu))};
    }
};

// The lanes of one image row and what is needed to sum them back. The lane
// arrays are sized once for a full row and filled by index.
struct RowBatch {
    std::vector<float> wi[3], wo[3], rgb[3], weight[3];
    size_t count = 0;
    std::vector<int> pixelX;      // covered pixels of the row
    std::vector<float> coverage;  // their coverage
    explicit RowBatch(size_t maxLanes) {
        for (int c = 0; c < 3; ++c)
            wi[c].resize(maxLanes), wo[c].resize(maxLanes), rgb[c].resize(maxLanes), weight[c].resize(maxLanes);
    }
    void clear() {
        count = 0;
        pixelX.clear(), coverage.clear();
    }
    void push(Vec in, Vec out, std::array<float, 3> w) {
        wi[0][count] = float(in.x), wi[1][count] = float(in.y), wi[2][count] = float(in.z);
        wo[0][count] = float(out.x), wo[1][count] = float(out.y), wo[2][count] = float(out.z);
        for (int c = 0; c < 3; ++c) weight[c][count] = w[c];
        ++count;
    }
    size_t lanes() const { return count; }
};

class SphereShader {
public:
    SphereShader(const Kernel& kernel, const SphereScene& scene)
        : scene_(scene), camera_(scene), light_(sphericalDirection(scene.lightThetaDeg, scene.lightPhiDeg)),
          alpha_(samplingRoughness(kernel)),
          cosineSamples_(scene.sky == SkyModel::None ? 0 : (scene.skySamples + 1) / 2),
          ggxSamples_(scene.sky == SkyModel::None ? 0 : scene.skySamples / 2) {}

    int lanesPerPixel() const { return 1 + cosineSamples_.size() + ggxSamples_.size(); }

    // Fills `batch` with the lanes of the covered pixels of row y.
    void buildRow(int y, RowBatch& batch) const {
        batch.clear();
        double R = camera_.radiusPixels();
        for (int x = 0; x < scene_.size; ++x) {
            double sx = camera_.diskX(x), sy = camera_.diskY(y);
            double rho = std::sqrt(sx * sx + sy * sy);
            double coverage = std::clamp(R - rho * R + 0.5, 0.0, 1.0);
            if (coverage <= 0) continue;
            if (rho > kMaxDiskRadius) sx *= kMaxDiskRadius / rho, sy *= kMaxDiskRadius / rho, rho = kMaxDiskRadius;
            batch.pixelX.push_back(x);
            batch.coverage.push_back(float(coverage));
            Vec n = sx * camera_.right + sy * camera_.up + std::sqrt(1 - rho * rho) * camera_.view;
            pushPixel(n, uint64_t(y) * uint64_t(scene_.size) + uint64_t(x), batch);
        }
    }

    // Sums the weighted kernel values of the row into the image.
    void accumulateRow(int y, const RowBatch& batch, SphereImage& image) const {
        size_t lane = 0;
        int per = lanesPerPixel();
        for (size_t p = 0; p < batch.pixelX.size(); ++p) {
            int x = batch.pixelX[p];
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int j = 0; j < per; ++j) sum += double(batch.rgb[c][lane + j]) * batch.weight[c][lane + j];
                image.at(x, y, c) = float(sum);
            }
            image.coverage[size_t(y) * scene_.size + x] = batch.coverage[p];
            lane += per;
        }
    }

private:
    void pushPixel(Vec n, uint64_t pixelIndex, RowBatch& batch) const {
        // Tangent along the latitude circle around world +Y (the
        // anisotropy direction); at the poles any perpendicular will do.
        Vec t = cross(kWorldUp, n);
        t = dot(t, t) < 1e-12 ? normalize(cross(Vec{1, 0, 0}, n)) : normalize(t);
        Vec b = cross(n, t);
        auto toLocal = [&](Vec d) { return Vec{dot(d, t), dot(d, b), dot(d, n)}; };
        auto toWorld = [&](Vec d) { return d.x * t + d.y * b + d.z * n; };
        Vec wo = toLocal(camera_.view);

        Vec wl = toLocal(light_);
        float lightWeight = float(scene_.lightIrradiance * std::max(0.0, wl.z));
        batch.push(wl, wo, {lightWeight, lightWeight, lightWeight});
        if (cosineSamples_.size() == 0) return;

        uint64_t h = splitMix64(pixelIndex);
        double du = double(h >> 11) * 0x1p-53;
        double angle = 2 * kPi * double(splitMix64(h) >> 11) * 0x1p-53;
        double cr = std::cos(angle), sr = std::sin(angle);
        double ax = alpha_[0], ay = alpha_[1];
        double mCos = cosineSamples_.size(), mGgx = ggxSamples_.size();
        // Multi-sample balance heuristic: every sample, whichever strategy
        // drew it, is weighted by L cos / (sum_k M_k p_k), with
        //   p_cos = cos / pi,  p_ggx = D(h) (n.h) / (4 wo.h),  h = s / |s|, s = wi + wo.
        // p_ggx is formed from s without normalizing it: with
        // e = s.x^2/ax^2 + s.y^2/ay^2 + s.z^2,  D(h) (n.h) = s.z |s|^4 / (pi ax ay e^2 |s|)
        // and wo.h = wo.s / |s|, so p_ggx = s.z (s.s)^2 / (4 pi ax ay e^2 wo.s).
        // (This loop is most of the renderer's own time: one division per sample.)
        double invAx2 = 1 / (ax * ax), invAy2 = 1 / (ay * ay), ggxScale = mGgx / (4 * kPi * ax * ay);
        auto pushSky = [&](Vec in) {
            std::array<float, 3> w{0, 0, 0};
            if (in.z > 0) {
                double densityTimesPi = mCos * in.z;  // (sum_k M_k p_k) * pi
                Vec sum = in + wo;
                double os = dot(wo, sum);
                if (mGgx > 0 && os > 0) {
                    double ss = dot(sum, sum);
                    double e = sum.x * sum.x * invAx2 + sum.y * sum.y * invAy2 + sum.z * sum.z;
                    densityTimesPi += kPi * ggxScale * sum.z * ss * ss / (e * e * os);
                }
                double scale = kPi * in.z / densityTimesPi;
                std::array<float, 3> L = skyRadiance(scene_, toWorld(in));
                for (int c = 0; c < 3; ++c) w[c] = float(L[c] * scale);
            } else {
                in = Vec{0, 0, 1};  // below the horizon: contributes nothing
            }
            batch.push(in, wo, w);
        };
        for (int i = 0; i < cosineSamples_.size(); ++i) pushSky(cosineSamples_.cosineDirection(i, du, cr, sr));
        for (int i = 0; i < ggxSamples_.size(); ++i) {
            // Stretching a cosine-distributed direction by (ax, ay) gives
            // microfacet normals distributed as D_ggx(h) cos(theta_h).
            Vec c = ggxSamples_.cosineDirection(i, du, cr, sr);
            Vec hv = normalize(Vec{ax * c.x, ay * c.y, c.z});
            double oh = dot(wo, hv);
            pushSky(oh > 0 ? 2 * oh * hv - wo : Vec{0, 0, -1});
        }
    }

    const SphereScene& scene_;
    Camera camera_;
    Vec light_;
    std::array<double, 2> alpha_;
    PointSet cosineSamples_, ggxSamples_;
};

double srgbEncode(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
}

}  // namespace

double acesFilmic(double x) {
    x = std::max(0.0, x);
    return std::clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

std::string validateScene(const SphereScene& s) {
    if (s.size < 8 || s.size > 16384) return fmt::format("image size {} is outside 8 .. 16384", s.size);
    if (s.skySamples < 0 || s.skySamples > 65536)
        return fmt::format("sky samples {} is outside 0 .. 65536", s.skySamples);
    for (double a : {s.lightThetaDeg, s.lightPhiDeg, s.viewThetaDeg, s.viewPhiDeg, s.lightIrradiance, s.skyRadiance,
                     s.exposureEv})
        if (!std::isfinite(a)) return "scene values must be finite numbers";
    if (s.lightThetaDeg < 0 || s.lightThetaDeg > 180 || s.viewThetaDeg < 0 || s.viewThetaDeg > 180)
        return "theta must be in 0 .. 180 degrees";
    if (s.lightIrradiance < 0 || s.skyRadiance < 0) return "light and sky intensities must be >= 0";
    if (s.threads < 0 || s.threads > 1024) return fmt::format("threads {} is outside 0 .. 1024", s.threads);
    return "";
}

SphereImage renderSphere(const Kernel& kernel, const SphereScene& scene) {
    SphereImage image;
    image.size = scene.size;
    image.radiance.assign(size_t(scene.size) * scene.size * 3, 0.0f);
    image.coverage.assign(size_t(scene.size) * scene.size, 0.0f);
    SphereShader shader(kernel, scene);

    int threads = scene.threads ? scene.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    threads = std::min(threads, scene.size);
    std::atomic<int> nextRow{0};
    std::atomic<int64_t> invalid{0}, evaluations{0}, pixels{0}, kernelNanos{0};
    auto worker = [&] {
        RowBatch batch(size_t(scene.size) * shader.lanesPerPixel());
        for (int y; (y = nextRow.fetch_add(1)) < scene.size;) {
            shader.buildRow(y, batch);
            size_t n = batch.lanes();
            if (n == 0) continue;
            const float* wi[3] = {batch.wi[0].data(), batch.wi[1].data(), batch.wi[2].data()};
            const float* wo[3] = {batch.wo[0].data(), batch.wo[1].data(), batch.wo[2].data()};
            float* rgb[3] = {batch.rgb[0].data(), batch.rgb[1].data(), batch.rgb[2].data()};
            auto kernelStart = std::chrono::steady_clock::now();
            invalid += kernel.evalBatch(int64_t(n), wi, wo, nullptr, rgb);
            kernelNanos += std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                                                kernelStart).count();
            evaluations += int64_t(n);
            pixels += int64_t(batch.pixelX.size());
            shader.accumulateRow(y, batch, image);
        }
    };
    auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    image.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    image.stats.kernelSeconds = double(kernelNanos) * 1e-9;
    image.stats.threads = threads;
    image.stats.invalidLanes = invalid;
    image.stats.evaluations = evaluations;
    image.stats.pixels = pixels;
    return image;
}

std::string writeSphereImage(const SphereImage& image, const SphereScene& scene, const std::string& path) {
    std::string ext = OIIO::Filesystem::extension(path, false);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    bool linear = ext == "exr" || ext == "hdr";
    int n = image.size;
    OIIO::ImageSpec spec(n, n, linear ? 4 : 3, OIIO::TypeDesc::FLOAT);
    if (linear) spec.alpha_channel = 3;
    spec.attribute("Software", "facet render");
    double exposure = std::exp2(scene.exposureEv);
    constexpr double kBackground = 0.22;  // display-referred grey behind the sphere
    int channels = spec.nchannels;
    // The pixels in one buffer, handed to OpenImageIO at once (not a setpixel per pixel).
    std::vector<float> pixels(size_t(n) * n * channels);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            float cov = image.coverage[size_t(y) * n + x];
            float* px = &pixels[(size_t(y) * n + x) * channels];
            for (int c = 0; c < 3; ++c) {
                double L = image.at(x, y, c);
                px[c] = linear ? float(L * cov)
                               : float(srgbEncode(cov * acesFilmic(L * exposure) + (1 - cov) * kBackground));
            }
            if (linear) px[3] = cov;
        }
    OIIO::ImageBuf buf(spec, pixels.data());  // wraps the buffer; written below, before it goes away
    return writeImageFile(buf, path, linear ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
}

std::optional<std::array<double, 2>> highlightPixel(const SphereScene& scene) {
    Camera camera(scene);
    Vec h = normalize(sphericalDirection(scene.lightThetaDeg, scene.lightPhiDeg) + camera.view);
    if (!std::isfinite(h.x) || dot(h, camera.view) <= 0) return std::nullopt;
    double sx = dot(h, camera.right), sy = dot(h, camera.up);
    return std::array<double, 2>{(sx * kSphereFraction + 1) * scene.size / 2 - 0.5,
                                 (1 - sy * kSphereFraction) * scene.size / 2 - 0.5};
}

}  // namespace facet::preview
