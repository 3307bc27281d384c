// A C++ consumer of brdf_atlas.hpp, run by crates/ffi/tests/consumers.rs:
//
//     consumer-cpp EXPECTED.txt
//
// Reads the same expected.txt as consumer.c and checks the RAII wrapper:
// values and vectors bit for bit against the Rust library's, exceptions
// with the right status for bad calls, move semantics, and one Model shared
// by several std::threads giving the same bytes as serial calls.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "brdf_atlas.hpp"

namespace {

int failures = 0;

#define CHECK(cond, what)                                                                  \
    do {                                                                                   \
        if (!(cond)) {                                                                     \
            ++failures;                                                                    \
            std::cerr << "FAIL " << __FILE__ << ":" << __LINE__ << ": " << what << "\n";   \
        }                                                                                  \
    } while (0)

// The call must throw brdf_atlas::Error with `want` and a message containing `needle`.
#define EXPECT_ERROR(call, want, needle)                                                   \
    do {                                                                                   \
        try {                                                                              \
            (void)(call);                                                                  \
            CHECK(false, #call << " did not throw");                                       \
        } catch (const brdf_atlas::Error &e) {                                             \
            CHECK(e.status() == (want), #call << " -> " << e.status() << ": " << e.what()); \
            CHECK(std::string(e.what()).find(needle) != std::string::npos,                 \
                  #call << ": message " << e.what() << " lacks " << needle);               \
        }                                                                                  \
    } while (0)

// expected.txt: "key values... [path]" lines; several lines may share a key.
std::multimap<std::string, std::string> expected;

void load(const std::string &path) {
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        auto space = line.find(' ');
        expected.emplace(line.substr(0, space), line.substr(space + 1));
    }
}

std::vector<std::string> all(const std::string &key) {
    std::vector<std::string> out;
    auto range = expected.equal_range(key);
    for (auto it = range.first; it != range.second; ++it) {
        out.push_back(it->second);
    }
    if (out.empty()) {
        std::cerr << "expected.txt has no " << key << "\n";
        std::exit(2);
    }
    return out;
}

std::string one(const std::string &key) { return all(key).front(); }

// The line "key index ...", without "index ".
std::string indexed(const std::string &key, std::size_t index) {
    std::string prefix = std::to_string(index) + " ";
    for (const auto &line : all(key)) {
        if (line.compare(0, prefix.size(), prefix) == 0) {
            return line.substr(prefix.size());
        }
    }
    std::cerr << "expected.txt has no " << key << " " << index << "\n";
    std::exit(2);
}

// Numbers first, then an optional path (the rest of the line).
struct Fields {
    std::vector<double> numbers;
    std::string tail;
};

Fields fields(const std::string &text, std::size_t count) {
    Fields f;
    const char *p = text.c_str();
    for (std::size_t i = 0; i < count; ++i) {
        char *end = nullptr;
        f.numbers.push_back(std::strtod(p, &end));
        p = end;
    }
    while (*p == ' ') {
        ++p;
    }
    f.tail = p;
    return f;
}

std::vector<unsigned char> read_file(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), {});
}

bool same(double a, double b) {
    return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

bool table_matches(const std::vector<double> &table, const std::string &path) {
    auto file = read_file(path);
    return file.size() == 12 + table.size() * sizeof(double) &&
           std::memcmp(file.data() + 12, table.data(), table.size() * sizeof(double)) == 0;
}

void check_model(const brdf_atlas::Model &model) {
    CHECK(brdf_atlas::version() == one("version"), "version " << brdf_atlas::version());
    CHECK(model.latent_dim() == 2, "q " << model.latent_dim());
    std::size_t n = model.material_count();
    CHECK(n == std::stoul(one("count")), "count " << n);
    auto dims = model.dims();
    CHECK(model.table_len() == 3 * dims.theta_h * dims.theta_d * dims.phi_d, "table_len");
    for (std::size_t i = 0; i < n; ++i) {
        auto name = fields(indexed("name", i), 0).tail;
        CHECK(model.material_name(i) == name, "name " << i << ": " << model.material_name(i));
        auto xy = fields(indexed("latent", i), 2).numbers;
        auto got = model.latent_point(i);
        CHECK(got.size() == 2 && same(got[0], xy[0]) && same(got[1], xy[1]), "latent " << i);
    }
    EXPECT_ERROR(model.material_name(n), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "does not exist");
    auto v = model.view();
    auto want = fields(one("view"), 4).numbers;
    CHECK(same(v.x0, want[0]) && same(v.x1, want[1]) && same(v.y0, want[2]) &&
              same(v.y1, want[3]),
          "view");

    // Reconstruction, in memory and to a file.
    auto point = fields(all("point").front(), 2);
    double x = point.numbers[0], y = point.numbers[1];
    CHECK(table_matches(model.reconstruct(x, y), point.tail), "reconstruct");
    std::string out = fields(one("out_dir"), 0).tail + "/cpp.binary";
    model.save(x, y, out);
    CHECK(read_file(out) == read_file(point.tail), "save");
    auto far = fields(one("far"), 2);
    CHECK(table_matches(model.reconstruct(far.numbers[0], far.numbers[1]), far.tail), "far");

    // Evaluation, single and batched.
    std::vector<brdf_atlas::Vec3> wi, wo, want_rgb;
    for (const auto &line : all("pair")) {
        auto f = fields(line, 9).numbers;
        wi.push_back({f[0], f[1], f[2]});
        wo.push_back({f[3], f[4], f[5]});
        want_rgb.push_back({f[6], f[7], f[8]});
    }
    auto batch = model.eval_batch(x, y, wi, wo);
    CHECK(batch.size() == wi.size(), "batch size");
    for (std::size_t k = 0; k < wi.size(); ++k) {
        auto rgb = model.eval(x, y, wi[k], wo[k]);
        for (int c = 0; c < 3; ++c) {
            CHECK(same(rgb[c], want_rgb[k][c]), "eval pair " << k << " channel " << c);
            CHECK(same(batch[k][c], want_rgb[k][c]), "batch pair " << k << " channel " << c);
        }
    }
    CHECK(model.eval_batch(x, y, {}, {}).empty(), "empty batch");
    EXPECT_ERROR(model.eval_batch(x, y, wi, {}), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "differ");

    // Weights.
    auto w = model.weights(x, y);
    auto want_w = fields(one("weights"), n).numbers;
    CHECK(w.size() == n, "weights size");
    for (std::size_t i = 0; i < n && i < w.size(); ++i) {
        CHECK(same(w[i], want_w[i]), "weight " << i);
    }

    // Plausibility: what the C call gives, field for field; bad calls throw.
    BrdfAtlasPlausibility want_p{};
    CHECK(brdf_atlas_model_plausibility(model.get(), x, y, BRDF_ATLAS_BLEND_FLOOR, &want_p) ==
              BRDF_ATLAS_STATUS_OK,
          "C plausibility");
    auto p = model.plausibility(x, y);
    CHECK(same(p.clamped_reflectance, want_p.clamped_reflectance) &&
              same(p.clamped_values, want_p.clamped_values) && same(p.max_albedo, want_p.max_albedo) &&
              same(p.max_albedo_incidence, want_p.max_albedo_incidence) &&
              same(p.variance, want_p.variance) && same(p.weight_sum, want_p.weight_sum) &&
              p.plausible == want_p.plausible && p.low_confidence == want_p.low_confidence,
          "plausibility");
    EXPECT_ERROR(model.plausibility(x, y, 7), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "blend rule 7");

    // Maps: the default window, and another one.
    auto m = fields(one("map"), 3);
    auto map = model.albedo_map(std::size_t(m.numbers[0]), std::size_t(m.numbers[1]));
    auto bytes = read_file(m.tail);
    CHECK(bytes.size() == map.size() * sizeof(float) &&
              std::memcmp(bytes.data(), map.data(), bytes.size()) == 0,
          "default map");
    auto mv = fields(one("map_view"), 7).numbers;
    brdf_atlas::View view{mv[3], mv[4], mv[5], mv[6]};
    map = model.albedo_map(std::size_t(mv[0]), std::size_t(mv[1]), view, std::size_t(mv[2]));
    bytes = read_file(fields(one("map_view"), 7).tail);
    CHECK(bytes.size() == map.size() * sizeof(float) &&
              std::memcmp(bytes.data(), map.data(), bytes.size()) == 0,
          "map of another window");
    // The default rule's map is the soft floor's; the plausible rule has none.
    auto floor = model.albedo_map_with(std::size_t(mv[0]), std::size_t(mv[1]), view,
                                       std::size_t(mv[2]), BRDF_ATLAS_BLEND_FLOOR);
    CHECK(floor == map, "the floor's map is the default one");
    EXPECT_ERROR(model.albedo_map_with(4, 4, view, 0, BRDF_ATLAS_BLEND_PLAUSIBLE),
                 BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "has no map");
    EXPECT_ERROR(model.albedo_map(0, 10), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "map size");
    EXPECT_ERROR(model.albedo_map(100000, 100000), BRDF_ATLAS_STATUS_INVALID_ARGUMENT,
                 "map size");
    EXPECT_ERROR(model.albedo_map(4, 4, brdf_atlas::View{1, 0, 0, 1}),
                 BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "view");

    // Locate.
    auto loc = fields(one("locate"), 5).numbers;
    auto got = model.locate(fields(one("probe"), 0).tail);
    CHECK(got.nearest == std::size_t(loc[0]) && same(got.x, loc[1]) && same(got.y, loc[2]) &&
              same(got.rmse, loc[3]) && same(got.spread, loc[4]),
          "locate");
    EXPECT_ERROR(model.locate(fields(one("bad_merl"), 0).tail), BRDF_ATLAS_STATUS_BAD_MERL,
                 "bad.binary");

    // Bad coordinates throw; far ones are answered.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_ERROR(model.reconstruct(nan, 0), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT_ERROR(model.weights(0, -inf), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "finite");
    EXPECT_ERROR(model.eval(nan, nan, wi[0], wo[0]), BRDF_ATLAS_STATUS_INVALID_ARGUMENT,
                 "finite");
    EXPECT_ERROR(model.save(0, 0, ""), BRDF_ATLAS_STATUS_INVALID_ARGUMENT, "empty");
    CHECK(model.weights(-1e300, 1e300).size() == n, "far weights");
    std::vector<double> small(10);
    EXPECT_ERROR(model.reconstruct_into(x, y, small.data(), small.size()),
                 BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL, "buf");
}

void check_threads(const brdf_atlas::Model &model) {
    std::vector<std::vector<double>> serial;
    std::vector<std::pair<double, double>> points;
    for (const auto &line : all("point")) {
        auto f = fields(line, 2);
        points.emplace_back(f.numbers[0], f.numbers[1]);
        serial.push_back(model.reconstruct(f.numbers[0], f.numbers[1]));
        CHECK(table_matches(serial.back(), f.tail), "point " << points.size() - 1);
    }
    const int threads = 8, rounds = 3;
    std::vector<int> mismatches(threads, 0);
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) {
        pool.emplace_back([&, t] {
            for (int r = 0; r < rounds; ++r) {
                for (std::size_t k = 0; k < points.size(); ++k) {
                    std::size_t j = (k + t) % points.size();
                    if (model.reconstruct(points[j].first, points[j].second) != serial[j]) {
                        ++mismatches[t];
                    }
                }
            }
        });
    }
    for (auto &th : pool) {
        th.join();
    }
    for (int t = 0; t < threads; ++t) {
        CHECK(mismatches[t] == 0, "thread " << t << ": " << mismatches[t] << " differ");
    }
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 2) {
        std::cerr << "usage: " << argv[0] << " EXPECTED.txt\n";
        return 2;
    }
    load(argv[1]);
    EXPECT_ERROR(brdf_atlas::Model(fields(one("missing"), 0).tail), BRDF_ATLAS_STATUS_IO,
                 "missing.model");
    EXPECT_ERROR(brdf_atlas::Model(fields(one("corrupt"), 0).tail), BRDF_ATLAS_STATUS_BAD_FILE,
                 "corrupt.model");
    try {
        brdf_atlas::Model opened(fields(one("model"), 0).tail);
        brdf_atlas::Model model(std::move(opened));
        // A moved-from model is empty: its calls throw, they do not crash.
        EXPECT_ERROR(opened.material_count(), BRDF_ATLAS_STATUS_NULL_ARGUMENT, "model");
        CHECK(opened.get() == nullptr && model.get() != nullptr, "move");
        check_model(model);
        check_threads(model);
        brdf_atlas::Model other(fields(one("model"), 0).tail);
        other = std::move(model);  // frees other's handle, takes model's
        CHECK(other.material_count() == std::stoul(one("count")), "move assignment");
    } catch (const brdf_atlas::Error &e) {
        CHECK(false, "unexpected error " << e.status() << ": " << e.what());
    }
    if (failures != 0) {
        std::cerr << failures << " checks failed\n";
        return 1;
    }
    std::cout << "all checks passed\n";
    return 0;
}
