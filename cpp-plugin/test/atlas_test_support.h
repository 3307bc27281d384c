// Helpers of the Qt Test of the brdf-atlas map widget (tst_atlasmap.cpp):
// the C library's own answers, through handles of the test's own (the
// reference tables, plausibility and maps the widget is checked against),
// the checks of the panel's plausibility line and of a map against them,
// file helpers (a glTF binary's JSON among them), and the user's steps that several tests repeat (Validate,
// choosing a blend rule).
#ifndef BRDF_ATLAS_TEST_SUPPORT_H
#define BRDF_ATLAS_TEST_SUPPORT_H

#include <QComboBox>
#include <QFile>
#include <QImage>
#include <QJsonDocument>
#include <QJsonObject>
#include <QLabel>
#include <QSignalSpy>
#include <QtEndian>
#include <QtTest>

#include <cstring>
#include <vector>

#include "AtlasMapWidget.h"
#include "AtlasStatus.h"

// The C library's own answer at (x, y), through a handle of its own: under
// the library's default rule, the soft floor, from the plain
// brdf_atlas_model_reconstruct; under another, from _reconstruct_with.
inline std::vector<double> referenceTable(const QString &model, double x, double y,
                                          std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR) {
    BrdfAtlasModel *h = nullptr;
    if (brdf_atlas_model_open(model.toUtf8().constData(), &h) != BRDF_ATLAS_STATUS_OK) {
        qFatal("brdf_atlas_model_open: %s", brdf_atlas_last_error_message());
    }
    std::size_t len = 0;
    brdf_atlas_model_table_len(h, &len);
    std::vector<double> t(len);
    std::size_t written = 0;
    const BrdfAtlasStatus s = blend == BRDF_ATLAS_BLEND_FLOOR
                                  ? brdf_atlas_model_reconstruct(h, x, y, t.data(), t.size(), &written)
                                  : brdf_atlas_model_reconstruct_with(h, x, y, blend, t.data(), t.size(), &written);
    if (s != BRDF_ATLAS_STATUS_OK || written != len) {
        qFatal("brdf_atlas_model_reconstruct: %s", brdf_atlas_last_error_message());
    }
    brdf_atlas_model_free(h);
    return t;
}

inline QByteArray readAll(const QString &path) {
    QFile f(path);
    if (!f.open(QIODevice::ReadOnly)) qFatal("cannot read %s", qPrintable(path));
    return f.readAll();
}

// The JSON chunk of a glTF binary (.glb): the first chunk, after the
// 12-byte header and the chunk's length and type.
inline QJsonObject glbJson(const QString &path) {
    const QByteArray glb = readAll(path);
    if (!glb.startsWith("glTF") || glb.mid(16, 4) != "JSON") qFatal("%s is not a glTF binary", qPrintable(path));
    return QJsonDocument::fromJson(glb.mid(20, int(qFromLittleEndian<quint32>(glb.constData() + 12)))).object();
}

// The C library's plausibility at (x, y), through a handle of its own.
inline BrdfAtlasPlausibility referencePlausibility(const QString &model, double x, double y,
                                                   std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR) {
    BrdfAtlasModel *h = nullptr;
    if (brdf_atlas_model_open(model.toUtf8().constData(), &h) != BRDF_ATLAS_STATUS_OK) {
        qFatal("brdf_atlas_model_open: %s", brdf_atlas_last_error_message());
    }
    BrdfAtlasPlausibility p{};
    if (brdf_atlas_model_plausibility(h, x, y, blend, &p) != BRDF_ATLAS_STATUS_OK) {
        qFatal("brdf_atlas_model_plausibility: %s", brdf_atlas_last_error_message());
    }
    brdf_atlas_model_free(h);
    return p;
}

// Rewrite `path` in place (the same file truncated, then written), as `cp`
// or a shell redirection over it does.
inline void rewriteInPlace(const QString &path, const QByteArray &bytes) {
    QFile f(path);
    if (!f.open(QIODevice::WriteOnly | QIODevice::Truncate) || f.write(bytes) != bytes.size())
        qFatal("cannot rewrite %s", qPrintable(path));
}

// Press Validate and wait for the outcome. Returns the failure message, or
// empty.
inline QString validateAtMarker(AtlasPanel *panel) {
    QSignalSpy done(panel, &AtlasPanel::reconstructed);
    QSignalSpy failed(panel, &AtlasPanel::failed);
    QTest::mouseClick(panel->validateButton(), Qt::LeftButton);
    if (!QTest::qWaitFor([&] { return done.count() + failed.count() > 0; }, 120000))
        qFatal("no outcome from Validate");
    return failed.isEmpty() ? QString() : failed.first().first().toString();
}

// Click the view half-way between its first two materials, then Validate.
inline QString validateBetweenMaterials(AtlasPanel *panel) {
    AtlasMapView *view = panel->mapView();
    const QPointF mid = (view->materialPoints()[0] + view->materialPoints()[1]) / 2;
    QTest::mouseClick(view, Qt::LeftButton, Qt::NoModifier, view->latentToWidget(mid).toPoint());
    return validateAtMarker(panel);
}

// Choose the blend rule shown as `label` in the panel's combo box.
inline void chooseBlend(AtlasPanel *panel, const char *label) {
    QComboBox *box = panel->blendBox();
    const int i = box->findText(QString::fromUtf8(label));
    if (i < 0) qFatal("no blend rule \"%s\" in the panel", label);
    box->setCurrentIndex(i);
}

// The panel's plausibility line states what the library says at the
// marker: the same numbers, the verdict and its colour, low confidence.
inline void checkPlausibilityShown(const QString &model, AtlasPanel *panel,
                                   std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR) {
    const QPointF m = panel->mapView()->marker();
    const BrdfAtlasPlausibility want = referencePlausibility(model, m.x(), m.y(), blend);
    const AtlasReconstruction &r = panel->lastReconstruction();
    QCOMPARE(r.x, m.x());
    QCOMPARE(r.y, m.y());
    // The numbers handed out with the table are the library's, bit for bit.
    QVERIFY(std::memcmp(&r.plausibility, &want, sizeof want) == 0);
    const QLabel *label = panel->plausibilityLabel();
    const QString text = label->text();
    qInfo("plausibility at (%g, %g): %s", m.x(), m.y(), qPrintable(text));
    QVERIFY(label->isVisibleTo(panel) && label->isEnabled());
    QCOMPARE(text, atlasPlausibilityText(want));
    const QString share =
        want.clamped_reflectance > 0 ? atlasPercentText(want.clamped_reflectance) : QStringLiteral("none");
    QVERIFY2(text.contains(share + " of the reflectance") &&
                 text.contains(QString::number(want.max_albedo_incidence, 'f', 0) + QChar(0x00B0)),
             qPrintable(text));
    QVERIFY2(text.contains(QString::number(want.max_albedo, 'f', 2)) ||
                 text.contains(QString::number(want.max_albedo, 'g', 6)),
             qPrintable(text));
    QCOMPARE(text.startsWith("Plausible: "), want.plausible != 0);
    QCOMPARE(text.startsWith("Not plausible: "), want.plausible == 0);
    QCOMPARE(label->styleSheet().contains("c03030"), want.plausible == 0);
    QCOMPARE(text.contains("knows little here"), want.low_confidence != 0);
    if (want.low_confidence) QVERIFY(text.contains(QString::number(want.variance, 'f', 2)));
}

// Whether `image`, a map of `window` shown by the view, is the library's map
// of that window pixel for pixel: its albedo map with `samples` quadrature
// samples (0: the full map's), faded by the map's variance.
inline bool sameAsLibraryMap(const brdf_atlas::Model &m, const QImage &image, const BrdfAtlasView &window,
                             std::size_t samples, bool preview = false) {
    const brdf_atlas::View v{window.x0, window.x1, window.y0, window.y1};
    const int w = image.width(), h = image.height();
    const brdf_atlas::Model::Map map = preview ? m.preview(w, h, v, samples) : m.map(w, h, v, samples);
    const std::vector<float> &rgb = map.rgb, &variance = map.variance;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (image.pixel(x, y) != atlasPixel(&rgb[3 * p], variance[p])) return false;
        }
    return true;
}

#endif  // BRDF_ATLAS_TEST_SUPPORT_H
