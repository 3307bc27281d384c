// AtlasStatus.h: what the brdf-atlas panel says about a latent point, in
// words for an artist: whether the model knows much there, and how physical
// the material reconstructed there is (brdf_atlas_model_plausibility); the
// analytic material fitted there (brdf_atlas_model_export); the blend rules
// Validate offers; and how a label of such words fits the panel.
//
// Plain functions of the library's numbers, kept apart from the widgets so
// that a test can put the same numbers into the same words.
#ifndef BRDF_ATLAS_STATUS_H
#define BRDF_ATLAS_STATUS_H

#include <QString>
#include <QVector>

#include <cstdint>

class QLabel;

#include "brdf_atlas.hpp"

/// A share (0..1) as a percentage for reading, not for computing: two
/// significant digits below 10%, whole percents above, "0%" for nothing and
/// "under 0.001%" for a trace (so that a trace never reads as none).
QString atlasPercentText(double share);

/// The status line where the model knows little (predictive variance
/// `variance` above BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE).
QString atlasLowConfidenceText(double variance);

/// One or two sentences on `p`: "Plausible: ..." or "Not plausible: ..."
/// (by `p.plausible`, and what is wrong first) with the share of the
/// reflectance clamped to 0 and the largest directional albedo with its
/// incidence; where `p.low_confidence`, a sentence saying that the model
/// knows little there, with the predictive variance.
QString atlasPlausibilityText(const brdf_atlas::Plausibility &p);

/// Where (x, y) is the marker of material `name` that the model does not
/// give back (`marker`, brdf_atlas::Model::marker): a sentence saying so,
/// with the model's albedo there over the material's ("Not black-fabric:
/// the model gives back 7.2x its albedo at its marker (worst channel)").
/// Empty where the point is no marker or the material is given back.
QString atlasMarkerText(const QString &name, const brdf_atlas::Model::Marker &marker);

/// The analytic fit `a` in words: its glTF parameters (base colour,
/// metallic, roughness, specular factor and colour, ior) with three decimals,
/// as `brdf-atlas export` prints them, and its table error: short enough
/// for the panel's status line in BRDF Explorer.
QString atlasAnalyticText(const brdf_atlas::Analytic &a);

/// What the table error of `a` measures, with the two baselines' (a
/// tooltip for the status line).
QString atlasAnalyticErrorTip(const brdf_atlas::Analytic &a);

/// The colour a label shows `p` in: empty (the palette's) when plausible,
/// the panel's error red when not.
QString atlasPlausibilityStyle(const brdf_atlas::Plausibility &p);

/// A blend rule Validate offers: the library's constant, its name in the
/// settings (the CLI's --blend name), its label in the panel, what the
/// status line adds after "reconstructed" (nothing for the default) and a
/// tooltip saying what it does.
struct AtlasBlendChoice {
    std::int32_t rule;
    QString key, label, said, tip;
};

/// The blend rules Validate offers, in the panel's order: the library's
/// default, the soft floor (the material the map draws), then the GP's
/// blend and the stepped plausible rule.
const QVector<AtlasBlendChoice> &atlasBlendChoices();

/// The choice of `rule`; the default's for a rule not offered.
const AtlasBlendChoice &atlasBlendChoice(std::int32_t rule);

/// The style sheet of the panel's error texts.
QString atlasErrorStyle();

/// Give the word-wrapped `label` a minimum height of its text wrapped at
/// `width` pixels, and of at least `minLines` lines: a layout then never
/// squeezes it below what its text needs at that width.
void atlasFitLabel(QLabel *label, int width, int minLines);

#endif  // BRDF_ATLAS_STATUS_H
