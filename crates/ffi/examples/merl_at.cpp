// merl_at: write the material at latent point (x, y) of a brdf-atlas model
// as a MERL .binary file. Usage: merl_at MODEL X Y OUT.binary
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "brdf_atlas.hpp"

static bool parse(const char *text, double *value) {
    char *end = nullptr;
    *value = std::strtod(text, &end);
    return end != text && *end == '\0' && std::isfinite(*value);
}

int main(int argc, char **argv) {
    double x = 0, y = 0;
    if (argc != 5 || !parse(argv[2], &x) || !parse(argv[3], &y)) {
        std::fprintf(stderr, "usage: merl_at MODEL X Y OUT.binary (X, Y finite numbers)\n");
        return 2;
    }
    try {
        brdf_atlas::Model model(argv[1]);
        model.save(x, y, argv[4]);
        brdf_atlas::Dims d = model.dims();
        std::printf("wrote %s: %zux%zux%zu, a blend of %zu materials at (%g, %g)\n", argv[4],
                    d.theta_h, d.theta_d, d.phi_d, model.material_count(), x, y);
    } catch (const brdf_atlas::Error &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
