// AtlasStatus.cpp: see AtlasStatus.h.
#include "AtlasStatus.h"

#include <QChar>
#include <QLabel>

#include <algorithm>

namespace {

// The bounds BrdfAtlasPlausibility::plausible checks (brdf_atlas.h): at most
// 1% of the reflectance clamped, and no directional albedo above 1 (a
// physical material reflects at most what it receives). Used only to say
// why a material is not plausible; the verdict is the library's.
constexpr double kClampLimit = 0.01;
constexpr double kAlbedoLimit = 1.0;

// An albedo with two decimals, or more where two would hide that it is
// above the limit (1.004 is not "1.00").
QString albedoText(double albedo) {
    QString text = QString::number(albedo, 'f', 2);
    if (albedo > kAlbedoLimit && text.toDouble() <= kAlbedoLimit) {
        text = QString::number(albedo, 'g', 6);
    }
    return text;
}

QString degreesText(double degrees) { return QString::number(degrees, 'f', 0) + QChar(0x00B0); }

// "none" reads better than "0%" at the start of a clause.
QString clampedText(double share) {
    return share > 0 ? atlasPercentText(share) : QStringLiteral("none");
}

}  // namespace

QString atlasPercentText(double share) {
    const double percent = 100 * share;
    if (percent <= 0) return QStringLiteral("0%");
    if (percent < 0.001) return QStringLiteral("under 0.001%");
    // 'g' keeps two significant digits without an exponent from 0.001 up;
    // from 10 up whole percents say enough.
    return (percent < 10 ? QString::number(percent, 'g', 2) : QString::number(percent, 'f', 0)) +
           QLatin1Char('%');
}

QString atlasLowConfidenceText(double variance) {
    return QStringLiteral("The model knows little here (predictive variance %1 of 1): the "
                          "material is mostly the database's mean, faded on the map.")
        .arg(variance, 0, 'f', 2);
}

QString atlasPlausibilityText(const brdf_atlas::Plausibility &p) {
    const QString share = clampedText(p.clamped_reflectance);
    const QString albedo = albedoText(p.max_albedo), at = degreesText(p.max_albedo_incidence);
    QString text;
    if (p.plausible) {
        text = QStringLiteral("Plausible: %1 of the reflectance clamped, largest albedo %2 (at %3).")
                   .arg(share, albedo, at);
    } else {
        // What is wrong comes first; both numbers are always there.
        const bool negative = p.clamped_reflectance > kClampLimit;
        const bool bright = p.max_albedo > kAlbedoLimit;
        const QString clamped =
            (negative ? QStringLiteral("%1 of the reflectance is negative (clamped to 0)")
                      : QStringLiteral("%1 of the reflectance clamped to 0"))
                .arg(share);
        const QString largest =
            (bright ? QStringLiteral("largest albedo %1 at %2, above 1 (more light out than in)")
                    : QStringLiteral("largest albedo %1 (at %2)"))
                .arg(albedo, at);
        const bool brightFirst = bright && !negative;
        text = QStringLiteral("Not plausible: %1; %2.")
                   .arg(brightFirst ? largest : clamped, brightFirst ? clamped : largest);
    }
    if (p.low_confidence) {
        text += QStringLiteral(" The model knows little here (variance %1 of 1).")
                    .arg(p.variance, 0, 'f', 2);
    }
    return text;
}

QString atlasMarkerText(const QString &name, const brdf_atlas::Model::Marker &marker) {
    if (marker.material == SIZE_MAX || marker.given_back()) return QString();
    const double r = marker.albedo_ratio;
    const QString ratio = QString::number(r, 'f', r >= 10 ? 0 : (r >= 1 ? 1 : 2));
    return QStringLiteral("Not %1: the model gives back %2x its albedo at its marker (worst "
                          "channel, %3 off).")
        .arg(name, ratio, atlasPercentText(marker.albedo_error));
}

QString atlasAnalyticText(const brdf_atlas::Analytic &a) {
    auto n = [](double v) { return QString::number(v, 'f', 3); };
    auto rgb = [&](const double *c) { return QStringLiteral("(%1, %2, %3)").arg(n(c[0]), n(c[1]), n(c[2])); };
    return QStringLiteral("glTF fit: base colour %1, metallic %2, roughness %3, specular %4, specular "
                          "colour %5, ior %6; fit error %7 (table).")
        .arg(rgb(a.base_color), n(a.metallic), n(a.roughness), n(a.specular), rgb(a.specular_color),
             n(a.ior), QString::number(a.table_error, 'f', 4));
}

QString atlasAnalyticErrorTip(const brdf_atlas::Analytic &a) {
    return QStringLiteral("Fit error: RMS over a subsample of the table's bins of the log of the fit's "
                          "reflectance over the material's, cosine weighted. The same for one GGX lobe "
                          "over a Lambertian base: %1; for the Lambertian of the albedo: %2.")
        .arg(QString::number(a.single_lobe_table_error, 'f', 4),
             QString::number(a.lambertian_table_error, 'f', 4));
}

QString atlasPlausibilityStyle(const brdf_atlas::Plausibility &p) {
    return p.plausible ? QString() : atlasErrorStyle();
}

const QVector<AtlasBlendChoice> &atlasBlendChoices() {
    static const QVector<AtlasBlendChoice> choices = {
        {BRDF_ATLAS_BLEND_FLOOR, QStringLiteral("floor"), QStringLiteral("Soft floor"), QString(),
         QStringLiteral("The library's default, and the material the map draws: the GP's blend with "
                        "each value lifted smoothly onto a floor at 0.3 times a convex blend of the "
                        "materials. Never negative, so nothing is clamped; more accurate than the "
                        "GP's blend on held-out materials; no extra pass over the model's data.")},
        {BRDF_ATLAS_BLEND_GP, QStringLiteral("gp"), QStringLiteral("GP"), QStringLiteral(" (GP blend)"),
         QStringLiteral("The GP's own blend, the paper's reconstruction: between unlike materials its "
                        "weights take both signs, and values that come out negative are clamped to "
                        "0. The map draws the soft floor's material, not this one.")},
        {BRDF_ATLAS_BLEND_PLAUSIBLE, QStringLiteral("plausible"), QStringLiteral("Stepped"),
         QStringLiteral(" (stepped plausible rule)"),
         QStringLiteral("The stepped plausible rule: in each theta_h bin where the GP's blend would "
                        "be clamped, its weights moved towards a convex blend of the materials just "
                        "far enough that the clamp removes almost nothing, then further wherever "
                        "the material would reflect more light than it receives; one more pass "
                        "over the model's data. The map draws the soft floor's material, not this "
                        "one.")},
    };
    return choices;
}

const AtlasBlendChoice &atlasBlendChoice(std::int32_t rule) {
    for (const AtlasBlendChoice &c : atlasBlendChoices()) {
        if (c.rule == rule) return c;
    }
    return atlasBlendChoices().first();
}

QString atlasErrorStyle() { return QStringLiteral("color: #c03030"); }

void atlasFitLabel(QLabel *label, int width, int minLines) {
    // setMinimumHeight with the height it has is a no-op: no new layout
    // request, so fitting on every layout request settles.
    label->setMinimumHeight(std::max(minLines * label->fontMetrics().lineSpacing(),
                                     label->heightForWidth(std::max(1, width))));
}
