// SphereRender: shading a sphere with a compiled kernel (see SphereRender.h).
//
// The work is organized for the batched kernel: each image row becomes two
// batches of lanes (every covered pixel contributes 1 light lane, evaluated,
// and N sky lanes, drawn by the kernel's importance sampler), the kernel
// runs the whole row at once, and the weighted values are summed back into
// the pixels. Rows are handed out to the threads one at a time.
#include "SphereRender.h"

#include "ImageFiles.h"

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

double radicalInverse2(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i * 0x1p-32;
}

double radicalInverse3(uint32_t i) {
    double inverse = 0, scale = 1.0 / 3;
    for (; i; i /= 3, scale /= 3) inverse += double(i % 3) * scale;
    return inverse;
}

uint64_t splitMix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// The uniform numbers of a pixel's sky samples: one 3D point set (u0 picks
// the lobe, u1 and u2 place the direction: Hammersley in (u1, u2), the base-3
// radical inverse in u0) shifted per pixel modulo 1 (Cranley-Patterson), so
// that neighbouring pixels do not repeat one pattern.
struct SkyPointSet {
    std::vector<double> u[3];
    explicit SkyPointSet(int n) {
        for (int i = 0; i < n; ++i) {
            u[0].push_back(radicalInverse3(uint32_t(i)));
            u[1].push_back((i + 0.5) / n);
            u[2].push_back(radicalInverse2(uint32_t(i)));
        }
    }
    int size() const { return int(u[0].size()); }
    // Coordinate d of point i shifted by `shift`, as a float below 1 (the
    // sampler's domain is [0, 1)).
    float shifted(int d, int i, double shift) const {
        double v = u[d][size_t(i)] + shift;
        float f = float(v - std::floor(v));
        return f < 1.0f ? f : std::nextafter(1.0f, 0.0f);
    }
};

// A shading point's local frame: tangent, bitangent, normal in world space.
struct Frame {
    Vec t, b, n;
    Vec toLocal(Vec d) const { return {dot(d, t), dot(d, b), dot(d, n)}; }
    Vec toWorld(Vec d) const { return d.x * t + d.y * b + d.z * n; }
};

// The lanes of one image row and what is needed to sum them back, in two
// parts: one light lane per covered pixel, evaluated by the kernel, and N
// sky lanes per covered pixel, drawn by the kernel's importance sampler
// (weight = f cos / pdf). The arrays are sized once for a full row.
struct RowBatch {
    std::vector<float> wi[3], wo[3], rgb[3], lightWeight;              // light lanes
    std::vector<float> skyWo[3], skyU[3], skyWi[3], skyPdf, skyWeight[3];  // sky lanes
    size_t count = 0, skyCount = 0;
    std::vector<int> pixelX;      // covered pixels of the row
    std::vector<float> coverage;  // their coverage
    std::vector<Frame> frames;    // their local frames
    RowBatch(size_t pixels, size_t skyPerPixel) {
        for (int c = 0; c < 3; ++c) {
            wi[c].resize(pixels), wo[c].resize(pixels), rgb[c].resize(pixels);
            for (auto* v : {&skyWo[c], &skyU[c], &skyWi[c], &skyWeight[c]}) v->resize(pixels * skyPerPixel);
        }
        lightWeight.resize(pixels);
        skyPdf.resize(pixels * skyPerPixel);
    }
    void clear() {
        count = skyCount = 0;
        pixelX.clear(), coverage.clear(), frames.clear();
    }
    void pushLight(Vec in, Vec out, float weight) {
        wi[0][count] = float(in.x), wi[1][count] = float(in.y), wi[2][count] = float(in.z);
        wo[0][count] = float(out.x), wo[1][count] = float(out.y), wo[2][count] = float(out.z);
        lightWeight[count] = weight;
        ++count;
    }
    void pushSky(Vec out, const float u[3]) {
        skyWo[0][skyCount] = float(out.x), skyWo[1][skyCount] = float(out.y), skyWo[2][skyCount] = float(out.z);
        for (int d = 0; d < 3; ++d) skyU[d][skyCount] = u[d];
        ++skyCount;
    }
};

class SphereShader {
public:
    SphereShader(const SphereScene& scene)
        : scene_(scene), camera_(scene), light_(sphericalDirection(scene.lightThetaDeg, scene.lightPhiDeg)),
          skySamples_(scene.sky == SkyModel::None ? 0 : scene.skySamples) {}

    int skySamplesPerPixel() const { return skySamples_.size(); }

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

    // Sums the light lane (kernel value times irradiance cos) and the mean of
    // the sky lanes (sampler weight times the sky's radiance) into the image.
    void accumulateRow(int y, const RowBatch& batch, SphereImage& image) const {
        int per = skySamples_.size();
        for (size_t p = 0; p < batch.pixelX.size(); ++p) {
            int x = batch.pixelX[p];
            double sum[3];
            for (int c = 0; c < 3; ++c) sum[c] = double(batch.rgb[c][p]) * batch.lightWeight[p];
            double sky[3] = {0, 0, 0};
            for (size_t j = p * per; j < (p + 1) * per; ++j) {
                if (!(batch.skyPdf[j] > 0)) continue;  // no direction (the lane's weight is 0)
                Vec wi{batch.skyWi[0][j], batch.skyWi[1][j], batch.skyWi[2][j]};
                std::array<float, 3> L = skyRadiance(scene_, batch.frames[p].toWorld(wi));
                for (int c = 0; c < 3; ++c) sky[c] += double(batch.skyWeight[c][j]) * L[c];
            }
            for (int c = 0; c < 3; ++c) image.at(x, y, c) = float(sum[c] + (per ? sky[c] / per : 0.0));
            image.coverage[size_t(y) * scene_.size + x] = batch.coverage[p];
        }
    }

private:
    void pushPixel(Vec n, uint64_t pixelIndex, RowBatch& batch) const {
        // Tangent along the latitude circle around world +Y (the
        // anisotropy direction); at the poles any perpendicular will do.
        Vec t = cross(kWorldUp, n);
        t = dot(t, t) < 1e-12 ? normalize(cross(Vec{1, 0, 0}, n)) : normalize(t);
        Frame frame{t, cross(n, t), n};
        batch.frames.push_back(frame);
        Vec wo = frame.toLocal(camera_.view);
        Vec wl = frame.toLocal(light_);
        double cosine = scene_.lightThrough ? std::abs(wl.z) : std::max(0.0, wl.z);
        batch.pushLight(wl, wo, float(scene_.lightIrradiance * cosine));
        uint64_t h = splitMix64(pixelIndex);
        double shift[3];
        for (double& d : shift) {
            d = double(h >> 11) * 0x1p-53;
            h = splitMix64(h);
        }
        for (int i = 0; i < skySamples_.size(); ++i) {
            float u[3] = {skySamples_.shifted(0, i, shift[0]), skySamples_.shifted(1, i, shift[1]),
                          skySamples_.shifted(2, i, shift[2])};
            batch.pushSky(wo, u);
        }
    }

    const SphereScene& scene_;
    Camera camera_;
    Vec light_;
    SkyPointSet skySamples_;
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

SphereImage renderSphere(const Kernel& kernel, const SphereScene& scene, const SkySampler& sampler) {
    SphereImage image;
    image.size = scene.size;
    image.radiance.assign(size_t(scene.size) * scene.size * 3, 0.0f);
    image.coverage.assign(size_t(scene.size) * scene.size, 0.0f);
    SphereShader shader(scene);

    int threads = scene.threads ? scene.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    threads = std::min(threads, scene.size);
    std::atomic<int> nextRow{0};
    std::atomic<int64_t> invalid{0}, evaluations{0}, samples{0}, pixels{0}, kernelNanos{0};
    auto worker = [&] {
        RowBatch batch(size_t(scene.size), size_t(shader.skySamplesPerPixel()));
        for (int y; (y = nextRow.fetch_add(1)) < scene.size;) {
            shader.buildRow(y, batch);
            size_t n = batch.count, m = batch.skyCount;
            if (n == 0) continue;
            const float* wi[3] = {batch.wi[0].data(), batch.wi[1].data(), batch.wi[2].data()};
            const float* wo[3] = {batch.wo[0].data(), batch.wo[1].data(), batch.wo[2].data()};
            float* rgb[3] = {batch.rgb[0].data(), batch.rgb[1].data(), batch.rgb[2].data()};
            const float* skyWo[3] = {batch.skyWo[0].data(), batch.skyWo[1].data(), batch.skyWo[2].data()};
            const float* skyU[3] = {batch.skyU[0].data(), batch.skyU[1].data(), batch.skyU[2].data()};
            float* skyWi[3] = {batch.skyWi[0].data(), batch.skyWi[1].data(), batch.skyWi[2].data()};
            float* skyWeight[3] = {batch.skyWeight[0].data(), batch.skyWeight[1].data(), batch.skyWeight[2].data()};
            auto kernelStart = std::chrono::steady_clock::now();
            invalid += kernel.evalBatch(int64_t(n), wi, wo, nullptr, rgb);
            if (m && sampler) invalid += sampler(int64_t(m), skyWo, skyU, skyWi, batch.skyPdf.data(), skyWeight);
            else if (m) invalid += kernel.sampleBatch(int64_t(m), skyWo, skyU, nullptr, skyWi, batch.skyPdf.data(), skyWeight);
            kernelNanos += std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                                                kernelStart).count();
            evaluations += int64_t(n);
            samples += int64_t(m);
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
    image.stats.samples = samples;
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
