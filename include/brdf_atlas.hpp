// brdf_atlas.hpp: a header-only C++17 wrapper of brdf_atlas.h.
//
// brdf_atlas::Model owns a BrdfAtlasModel handle (move-only, freed in the
// destructor); its methods return values and std::vectors and throw
// brdf_atlas::Error, which carries the status and the library's one-line
// message, on any failure. A Model is safe to use from several threads at
// once (every method is const). Written by hand; the C header it includes is
// generated.
//
//     brdf_atlas::Model model("atlas.model");
//     std::vector<double> table = model.reconstruct(0.2, -0.4);
//     model.save(0.2, -0.4, "new.binary");
#ifndef BRDF_ATLAS_HPP
#define BRDF_ATLAS_HPP

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "brdf_atlas.h"

namespace brdf_atlas {

/// A failed call: the status and the library's message for it.
class Error : public std::runtime_error {
public:
    Error(BrdfAtlasStatus status, const std::string &message)
        : std::runtime_error(message), status_(status) {}

    /// The status the C function returned.
    BrdfAtlasStatus status() const noexcept { return status_; }

private:
    BrdfAtlasStatus status_;
};

/// Throw Error unless `status` is OK, with the calling thread's last message.
inline void check(BrdfAtlasStatus status) {
    if (status == BRDF_ATLAS_STATUS_OK) {
        return;
    }
    std::string message = brdf_atlas_last_error_message();
    if (message.empty()) {
        message = brdf_atlas_status_message(status);
    }
    throw Error(status, message);
}

/// The library's version, "MAJOR.MINOR.PATCH".
inline std::string version() { return brdf_atlas_version(); }

using View = BrdfAtlasView;
using Dims = BrdfAtlasDims;
using Location = BrdfAtlasLocation;
using Plausibility = BrdfAtlasPlausibility;
using Analytic = BrdfAtlasAnalytic;
using Vec3 = std::array<double, 3>;
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 arrays must be packed doubles");

/// An opened model. Move-only; the handle is released by the destructor.
class Model {
public:
    /// Open the model file at `path` (its store beside it). Throws Error.
    explicit Model(const std::string &path) {
        check(brdf_atlas_model_open(path.c_str(), &handle_));
    }

    ~Model() { brdf_atlas_model_free(handle_); }

    Model(const Model &) = delete;
    Model &operator=(const Model &) = delete;

    Model(Model &&other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}

    Model &operator=(Model &&other) noexcept {
        if (this != &other) {
            brdf_atlas_model_free(handle_);
            handle_ = std::exchange(other.handle_, nullptr);
        }
        return *this;
    }

    /// The C handle, still owned by this object (NULL after a move).
    const BrdfAtlasModel *get() const noexcept { return handle_; }

    /// Latent dimension q (2 for a map).
    std::size_t latent_dim() const {
        std::size_t q = 0;
        check(brdf_atlas_model_latent_dim(handle_, &q));
        return q;
    }

    /// Number N of input materials.
    std::size_t material_count() const {
        std::size_t n = 0;
        check(brdf_atlas_model_material_count(handle_, &n));
        return n;
    }

    /// Name of material `index`.
    std::string material_name(std::size_t index) const {
        std::size_t len = 0;
        check(brdf_atlas_model_material_name(handle_, index, nullptr, 0, &len));
        std::string name(len + 1, '\0');
        check(brdf_atlas_model_material_name(handle_, index, name.data(), name.size(), &len));
        name.resize(len);
        return name;
    }

    /// Latent coordinates of material `index` (q values).
    std::vector<double> latent_point(std::size_t index) const {
        std::vector<double> p(latent_dim());
        check(brdf_atlas_model_latent_point(handle_, index, p.data(), p.size()));
        return p;
    }

    /// The default window of a map.
    View view() const {
        View v{};
        check(brdf_atlas_model_view(handle_, &v));
        return v;
    }

    /// Table dims.
    Dims dims() const {
        Dims d{};
        check(brdf_atlas_model_dims(handle_, &d));
        return d;
    }

    /// Length of a table in doubles (3 * bins).
    std::size_t table_len() const {
        std::size_t len = 0;
        check(brdf_atlas_model_table_len(handle_, &len));
        return len;
    }

    /// The table at (x, y) in the MERL layout, raw MERL units (-1: unmeasured),
    /// under the library's default blend rule, the soft floor
    /// (BRDF_ATLAS_BLEND_FLOOR: the material albedo_map() shows).
    std::vector<double> reconstruct(double x, double y) const {
        std::vector<double> table(table_len());
        reconstruct_into(x, y, table.data(), table.size());
        return table;
    }

    /// The table at (x, y) under blend rule `blend` (BRDF_ATLAS_BLEND_FLOOR,
    /// as reconstruct(x, y); BRDF_ATLAS_BLEND_GP: the GP's own blend, clamped
    /// to >= 0; BRDF_ATLAS_BLEND_PLAUSIBLE: one more pass over the store).
    std::vector<double> reconstruct(double x, double y, std::int32_t blend) const {
        std::vector<double> table(table_len());
        check(brdf_atlas_model_reconstruct_with(handle_, x, y, blend, table.data(), table.size(),
                                                nullptr));
        return table;
    }

    /// The table at (x, y) into a caller buffer of `len` doubles.
    void reconstruct_into(double x, double y, double *buf, std::size_t len) const {
        check(brdf_atlas_model_reconstruct(handle_, x, y, buf, len, nullptr));
    }

    /// Write the table at (x, y) as a MERL .binary file, atomically.
    void save(double x, double y, const std::string &path) const {
        check(brdf_atlas_model_reconstruct_to_file(handle_, x, y, path.c_str()));
    }

    /// RGB reflectance at (x, y) for one direction pair; NaN where there is
    /// no value (below the horizon, unmeasured).
    Vec3 eval(double x, double y, const Vec3 &wi, const Vec3 &wo) const {
        Vec3 rgb{};
        check(brdf_atlas_model_eval(handle_, x, y, wi.data(), wo.data(), rgb.data()));
        return rgb;
    }

    /// RGB reflectance at (x, y) for every pair (wi[k], wo[k]); NaN where a
    /// pair has no value.
    std::vector<Vec3> eval_batch(double x, double y, const std::vector<Vec3> &wi,
                                 const std::vector<Vec3> &wo) const {
        if (wi.size() != wo.size()) {
            throw Error(BRDF_ATLAS_STATUS_INVALID_ARGUMENT,
                        "eval_batch: wi and wo differ in length");
        }
        std::vector<Vec3> rgb(wi.size());
        check(brdf_atlas_model_eval_batch(handle_, x, y, wi.empty() ? nullptr : wi[0].data(),
                                          wo.empty() ? nullptr : wo[0].data(), wi.size(),
                                          rgb.empty() ? nullptr : rgb[0].data(),
                                          3 * rgb.size()));
        return rgb;
    }

    /// The GP's N blend weights at (x, y).
    std::vector<double> weights(double x, double y) const {
        std::vector<double> w(material_count());
        check(brdf_atlas_model_weights(handle_, x, y, w.data(), w.size()));
        return w;
    }

    /// The albedo map: width * height RGB triples, row 0 at the top of `view`,
    /// of the material reconstruct() gives. `samples` 0 is the library default.
    std::vector<float> albedo_map(std::size_t width, std::size_t height, const View &view,
                                  std::size_t samples = 0) const {
        return plain_map(width, height, &view, samples);
    }

    /// The albedo map of the default window.
    std::vector<float> albedo_map(std::size_t width, std::size_t height) const {
        return plain_map(width, height, nullptr, 0);
    }

    /// The albedo map of blend rule `blend`'s material: BRDF_ATLAS_BLEND_FLOOR
    /// (albedo_map()'s) or BRDF_ATLAS_BLEND_GP (the plausible rule has none).
    std::vector<float> albedo_map_with(std::size_t width, std::size_t height, const View &view,
                                       std::size_t samples, std::int32_t blend) const {
        if (width == 0 || height == 0 || width > BRDF_ATLAS_MAX_MAP_SIDE ||
            height > BRDF_ATLAS_MAX_MAP_SIDE) {
            check(brdf_atlas_model_albedo_map_with(handle_, width, height, &view, samples, blend,
                                                   nullptr, nullptr, 0));
        }
        std::vector<float> rgb(width * height * 3);
        check(brdf_atlas_model_albedo_map_with(handle_, width, height, &view, samples, blend,
                                               nullptr, rgb.data(), rgb.size()));
        return rgb;
    }

    /// albedo_map() that another thread can cancel by setting `cancel` to 1
    /// (and never back during the call): then it stops soon and throws
    /// Error with status BRDF_ATLAS_STATUS_CANCELLED.
    std::vector<float> albedo_map(std::size_t width, std::size_t height, const View &view,
                                  std::size_t samples,
                                  const std::atomic<std::int32_t> &cancel) const {
        const std::int32_t *flag = Model::flag(&cancel);
        if (width == 0 || height == 0 || width > BRDF_ATLAS_MAX_MAP_SIDE ||
            height > BRDF_ATLAS_MAX_MAP_SIDE) {
            check(brdf_atlas_model_albedo_map_cancellable(handle_, width, height, &view, samples,
                                                          flag, nullptr, 0));
        }
        std::vector<float> rgb(width * height * 3);
        check(brdf_atlas_model_albedo_map_cancellable(handle_, width, height, &view, samples, flag,
                                                      rgb.data(), rgb.size()));
        return rgb;
    }

    /// A map's albedo (width * height * 3 floats, as albedo_map()) and
    /// predictive variance (width * height floats, as variance_map(); the
    /// field's polynomial where the map is drawn from a field) from one
    /// call: what a viewer needs for a frame. `blend` as in
    /// albedo_map_with(); `cancel` as in the cancellable albedo_map().
    struct Map {
        std::vector<float> rgb;
        std::vector<float> variance;
    };
    Map map(std::size_t width, std::size_t height, const View &view, std::size_t samples = 0,
            std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR,
            const std::atomic<std::int32_t> *cancel = nullptr) const {
        const std::int32_t *flag = Model::flag(cancel);
        if (width == 0 || height == 0 || width > BRDF_ATLAS_MAX_MAP_SIDE ||
            height > BRDF_ATLAS_MAX_MAP_SIDE) {
            check(brdf_atlas_model_map(handle_, width, height, &view, samples, blend, flag,
                                       nullptr, 0, nullptr, 0));
        }
        Map out{std::vector<float>(width * height * 3), std::vector<float>(width * height)};
        check(brdf_atlas_model_map(handle_, width, height, &view, samples, blend, flag,
                                   out.rgb.data(), out.rgb.size(), out.variance.data(),
                                   out.variance.size()));
        return out;
    }

    /// What a viewer draws while its window moves (brdf_atlas_model_map_preview):
    /// from the prepared map or a field the model holds (map()'s pixels
    /// wherever map() draws from the same field), never building anything;
    /// elsewhere every pixel integrated with `samples` (at least 1) samples.
    Map preview(std::size_t width, std::size_t height, const View &view, std::size_t samples,
                std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR) const {
        if (width == 0 || height == 0 || width > BRDF_ATLAS_MAX_MAP_SIDE ||
            height > BRDF_ATLAS_MAX_MAP_SIDE) {
            check(brdf_atlas_model_map_preview(handle_, width, height, &view, samples, blend,
                                               nullptr, 0, nullptr, 0));
        }
        Map out{std::vector<float>(width * height * 3), std::vector<float>(width * height)};
        check(brdf_atlas_model_map_preview(handle_, width, height, &view, samples, blend,
                                           out.rgb.data(), out.rgb.size(), out.variance.data(),
                                           out.variance.size()));
        return out;
    }

    /// How many entries (fields, and regions whose exact field is over
    /// budget) the fields saved beside the model hold: 0 when there are
    /// none. Throws Error (BRDF_ATLAS_STATUS_BAD_FILE) when the file cannot
    /// be used (damaged, or written for another fit).
    std::size_t saved_fields() const {
        std::size_t count = 0;
        check(brdf_atlas_model_saved_fields(handle_, &count));
        return count;
    }

    /// Build the fields a width x height map of `view` draws from and save
    /// every field the model holds beside it (MODEL.fields), so that later
    /// maps, in any program, start from them. Seconds for 100 materials:
    /// run it off the GUI thread. Another thread can cancel it by setting
    /// `*cancel` to 1 (Error with BRDF_ATLAS_STATUS_CANCELLED, nothing saved).
    void prepare_map_fields(std::size_t width, std::size_t height, const View &view,
                            const std::atomic<std::int32_t> *cancel = nullptr) const {
        check(brdf_atlas_model_prepare_map_fields(handle_, width, height, &view, flag(cancel)));
    }

    /// prepare_map_fields() of what `brdf-atlas fit` saves: the default
    /// view's and [-3, 3]^2's fields (whose region holds a viewer's windows
    /// twice as wide as high), about 3 s for 100 materials.
    void prepare_fit_fields(const std::atomic<std::int32_t> *cancel = nullptr) const {
        check(brdf_atlas_model_prepare_fit_fields(handle_, flag(cancel)));
    }

    /// The GP's predictive variance of every pixel of the map of `view`
    /// (width * height floats, row 0 at the top): 0 at a material, 1 where
    /// the data say nothing, above 0.5 the model knows little.
    std::vector<float> variance_map(std::size_t width, std::size_t height,
                                    const View &view) const {
        if (width == 0 || height == 0 || width > BRDF_ATLAS_MAX_MAP_SIDE ||
            height > BRDF_ATLAS_MAX_MAP_SIDE) {
            check(brdf_atlas_model_variance_map(handle_, width, height, &view, nullptr, 0));
        }
        std::vector<float> v(width * height);
        check(brdf_atlas_model_variance_map(handle_, width, height, &view, v.data(), v.size()));
        return v;
    }

    /// The GP's predictive variance at (x, y) (no pass over the store).
    double variance(double x, double y) const {
        double v = 0;
        check(brdf_atlas_model_confidence(handle_, x, y, &v, nullptr));
        return v;
    }

    /// A material's marker at (x, y) and how the model gives it back there
    /// (brdf_atlas_model_marker).
    struct Marker {
        /// The material's index; SIZE_MAX where (x, y) is no marker (or the
        /// model records no figures).
        std::size_t material;
        /// The largest relative albedo error of the three channels.
        double albedo_error;
        /// The model's albedo over the material's in that channel.
        double albedo_ratio;
        /// Whether (x, y) is a marker whose material the model gives back
        /// (albedo within BRDF_ATLAS_GIVES_BACK in every channel).
        bool given_back() const {
            return material != SIZE_MAX && albedo_error <= BRDF_ATLAS_GIVES_BACK;
        }
    };

    /// Whether (x, y) is a material's marker, and how the model gives the
    /// material back there (no pass over the store).
    Marker marker(double x, double y) const {
        Marker m{SIZE_MAX, 0, 0};
        check(brdf_atlas_model_marker(handle_, x, y, &m.material, &m.albedo_error,
                                      &m.albedo_ratio));
        return m;
    }

    /// How physical the material at (x, y) is under blend rule `blend`
    /// (BRDF_ATLAS_BLEND_FLOOR: the table reconstruct() gives) and what the
    /// model knows there. Reads the whole store once, as reconstruct() does.
    Plausibility plausibility(double x, double y,
                              std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR) const {
        Plausibility p{};
        check(brdf_atlas_model_plausibility(handle_, x, y, blend, &p));
        return p;
    }

    /// The glTF parameters `brdf-atlas export` fits to the material at
    /// (x, y), and the fit's table errors. Takes one to a few seconds.
    Analytic fit_analytic(double x, double y) const {
        Analytic a{};
        check(brdf_atlas_model_fit_analytic(handle_, x, y, &a));
        return a;
    }

    /// Fit the material at (x, y) as fit_analytic() does and write it into
    /// the existing directory `dir` as STEM.glb, STEM.mtlx,
    /// STEM.mitsuba.json and STEM.fit.json (brdf_atlas_model_export); returns
    /// the parameters written.
    Analytic export_analytic(double x, double y, const std::string &dir,
                             const std::string &stem) const {
        Analytic a{};
        check(brdf_atlas_model_export(handle_, x, y, dir.c_str(), stem.c_str(), &a));
        return a;
    }

    /// Where the MERL file at `merl_path` lands.
    Location locate(const std::string &merl_path) const {
        Location l{};
        check(brdf_atlas_model_locate(handle_, merl_path.c_str(), &l));
        return l;
    }

private:
    /// A cancel flag as the C library takes it (NULL: none). The library
    /// reads it atomically; it never writes it.
    static const std::int32_t *flag(const std::atomic<std::int32_t> *cancel) {
        static_assert(sizeof(std::atomic<std::int32_t>) == sizeof(std::int32_t) &&
                          std::atomic<std::int32_t>::is_always_lock_free,
                      "the library reads the flag as a lock-free 32-bit atomic");
        return reinterpret_cast<const std::int32_t *>(cancel);
    }

    std::vector<float> plain_map(std::size_t width, std::size_t height, const View *view,
                                 std::size_t samples) const {
        if (width == 0 || height == 0 || width > BRDF_ATLAS_MAX_MAP_SIDE ||
            height > BRDF_ATLAS_MAX_MAP_SIDE) {
            // Not worth allocating for: let the library say what is wrong.
            check(brdf_atlas_model_albedo_map(handle_, width, height, view, samples, nullptr, 0));
        }
        std::vector<float> rgb(width * height * 3);
        check(brdf_atlas_model_albedo_map(handle_, width, height, view, samples, rgb.data(),
                                          rgb.size()));
        return rgb;
    }

    BrdfAtlasModel *handle_ = nullptr;
};

}  // namespace brdf_atlas

#endif  // BRDF_ATLAS_HPP
