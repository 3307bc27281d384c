// Qt Test of the brdf-atlas map widget, driven like a user: hover a
// reference point, zoom with the wheel, drag (a preview of every window on
// the way, the library's map pixel for pixel, then the full map; the
// frames' delays are printed), click, press Validate, wait
// for the reconstruction off the GUI thread, and check the table against
// the C library called directly (bit for bit), then save it and compare
// with the library's own writer byte for byte, and export the analytic
// material there (the parameters shown are the library's fit). Validate makes the default
// rule's material (the soft floor), or the GP's or the stepped rule's when
// chosen in the panel, which remembers the choice. Under Validate the panel
// states the material's plausibility: the numbers of
// brdf_atlas_model_plausibility called directly at the same point, in red
// where the library says the material is not plausible, greyed once the
// marker moves on. Grabs the widget to a PNG, and again squeezed to its
// minimum size, where every text must still show whole.
// Every way a model fails to open is shown in the panel, naming the file.
// Zoomed far out, the map fades where the model knows little, by the
// library's rule, and a click there says so in the status line.
// A model without its map's fields gets them built and saved beside it.
// Last, a second panel on a copy of the model whose store is rewritten in
// place while it is open: Validate and the map show the library's message,
// the last reconstruction stays usable, and reopening the model recovers.
//
// Environment: BRDF_ATLAS_TEST_MODEL (a 2-D model file, required),
// BRDF_ATLAS_ARTEFACTS (directory for the screenshot; default ".").
// Run with QT_QPA_PLATFORM=offscreen on a machine without a display.
#include <QComboBox>
#include <QDateTime>
#include <QDir>
#include <QFile>
#include <QJsonArray>
#include <QLabel>
#include <QLayout>
#include <QProgressBar>
#include <QPushButton>
#include <QScrollArea>
#include <QSettings>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QToolTip>
#include <QtTest>

#include <cmath>
#include <cstring>

#include "AtlasMapWidget.h"
#include "AtlasStatus.h"
#include "atlas_test_support.h"

class TestAtlasMap : public QObject {
    Q_OBJECT
private:
    QString modelPath_;
    QTemporaryDir settings_;
    AtlasPanel *panel_ = nullptr;
    AtlasMapView *view_ = nullptr;

    // Wait for the map of the window shown now (layouts settled first).
    void waitForMap() {
        auto current = [this] {
            const BrdfAtlasView w = view_->window(), m = view_->mapWindow();
            return !view_->mapPending() && m.x0 == w.x0 && m.x1 == w.x1 && m.y0 == w.y0 &&
                   m.y1 == w.y1;
        };
        QTest::qWait(50);
        QTRY_VERIFY_WITH_TIMEOUT(current(), 60000);
        QVERIFY(!view_->mapImage().isNull());
    }

private slots:
    void initTestCase() {
        modelPath_ = qEnvironmentVariable("BRDF_ATLAS_TEST_MODEL");
        QVERIFY2(!modelPath_.isEmpty(), "set BRDF_ATLAS_TEST_MODEL to a 2-D brdf-atlas model file");
        // The panels' settings in a directory of the test's own, empty at the
        // start: the defaults apply, and the user's settings stay as they are.
        QVERIFY(settings_.isValid());
        QSettings::setPath(QSettings::NativeFormat, QSettings::UserScope, settings_.path());
        panel_ = new AtlasPanel;
        view_ = panel_->mapView();
        // Tall enough that the marker between the first two materials stays
        // in view once the texts under the map have wrapped.
        panel_->resize(360, 500);
        panel_->show();
        QVERIFY(QTest::qWaitForWindowExposed(panel_));
        QSignalSpy opened(panel_, &AtlasPanel::modelOpened);
        QSignalSpy failed(panel_, &AtlasPanel::failed);
        panel_->openModel(modelPath_);
        QVERIFY(panel_->busy());
        QTRY_VERIFY_WITH_TIMEOUT(opened.count() + failed.count() > 0, 60000);
        QVERIFY2(failed.isEmpty(), failed.isEmpty() ? "" : qPrintable(failed.first().first().toString()));
        waitForMap();
    }

    void cleanupTestCase() { delete panel_; }

    void referencePointsAreTheModelsMaterials() {
        brdf_atlas::Model m(modelPath_.toStdString());
        QCOMPARE(std::size_t(view_->materialPoints().size()), m.material_count());
        for (int i = 0; i < view_->materialPoints().size(); ++i) {
            const std::vector<double> p = m.latent_point(i);
            QCOMPARE(view_->materialPoints()[i], QPointF(p[0], p[1]));
            QCOMPARE(view_->materialNames()[i], QString::fromStdString(m.material_name(i)));
        }
        // The map has contours and is not one flat colour.
        QVERIFY(view_->contours().size() > 10);
        const QImage &img = view_->mapImage();
        QSet<QRgb> colours;
        for (int y = 0; y < img.height(); y += 7)
            for (int x = 0; x < img.width(); x += 7) colours.insert(img.pixel(x, y));
        QVERIFY2(colours.size() > 20, qPrintable(QString::number(colours.size())));
    }

    void hoverShowsTheName() {
        const int i = view_->materialPoints().size() / 2;
        const QPoint at = view_->latentToWidget(view_->materialPoints()[i]).toPoint();
        QTest::mouseMove(view_, at);
        QTRY_COMPARE(view_->hoveredMaterial(), i);
        QVERIFY(!view_->labelRect(i).isEmpty());
        // Away from every point: no name.
        QTest::mouseMove(view_, QPoint(1, 1));
        QTRY_COMPARE(view_->hoveredMaterial(), -1);
    }

    void hoverNameStaysInside() {
        // Each material's point brought next to a corner of the view (right
        // and top edges, then left and bottom): its name is drawn inside the
        // widget, whole, beside the point.
        const QPointF centre = view_->centre();
        const double scale = view_->scale();
        const QFontMetricsF fm(view_->font());
        const QPointF corners[] = {QPointF(view_->width() - 3, 3), QPointF(3, view_->height() - 3)};
        for (int i = 0; i < view_->materialPoints().size(); ++i) {
            for (const QPointF &corner : corners) {
                const QPointF p = view_->materialPoints()[i];
                // latentToWidget(p) == corner: p lies that far from the centre.
                view_->setWindow(QPointF(p.x() - (corner.x() - view_->width() / 2.0) * scale,
                                         p.y() + (corner.y() - view_->height() / 2.0) * scale),
                                 scale);
                const QPoint at = view_->latentToWidget(p).toPoint();
                QVERIFY(view_->rect().contains(at));
                QTest::mouseMove(view_, at);
                QTRY_VERIFY(view_->hoveredMaterial() >= 0);
                const int h = view_->hoveredMaterial();
                const QRectF box = view_->labelRect(h);
                QVERIFY2(QRectF(view_->rect()).contains(box),
                         qPrintable(QStringLiteral("%1: %2,%3 %4x%5 in %6x%7")
                                        .arg(view_->materialNames()[h])
                                        .arg(box.x()).arg(box.y()).arg(box.width()).arg(box.height())
                                        .arg(view_->width()).arg(view_->height())));
                QVERIFY(box.width() >= std::min(fm.horizontalAdvance(view_->materialNames()[h]),
                                                double(view_->width()) - 8));
                // Beside the point, not on it.
                QVERIFY(!box.contains(view_->latentToWidget(view_->materialPoints()[h])));
            }
        }
        QTest::mouseMove(view_, QPoint(1, 1));
        view_->setWindow(centre, scale);
        waitForMap();
    }

    void mapSizeDoesNotDependOnTheTexts() {
        // A status line of many lines and the busy bar leave the map as it
        // is: the texts scroll in their box of fixed height instead.
        const QSize before = view_->size();
        const int boxHeight = panel_->textsBox()->height();
        const QString status = panel_->statusLabel()->text();
        QStringList lines;
        for (int k = 0; k < 4 * AtlasPanel::kTextLines; ++k) lines << QStringLiteral("line %1 of a long status").arg(k);
        panel_->statusLabel()->setText(lines.join('\n'));
        panel_->progressBar()->setVisible(true);
        QTest::qWait(100);  // the layouts settle
        QCOMPARE(view_->size(), before);
        QCOMPARE(panel_->textsBox()->height(), boxHeight);
        // The whole text is there, scrolled to.
        QVERIFY(panel_->textsBox()->widget()->height() > panel_->textsBox()->viewport()->height());
        QVERIFY(panel_->statusLabel()->height() >= panel_->statusLabel()->heightForWidth(panel_->statusLabel()->width()));
        QVERIFY(!view_->mapPending());  // nothing recomputed
        panel_->progressBar()->setVisible(false);
        panel_->statusLabel()->setText(status);
        QTest::qWait(100);
        QCOMPARE(view_->size(), before);
    }

    void wheelZoomsAboutTheCursor() {
        const QPointF at(view_->width() * 0.3, view_->height() * 0.6);
        const QPointF before = view_->widgetToLatent(at);
        const double scale = view_->scale();
        QWheelEvent wheel(at, view_->mapToGlobal(at.toPoint()), QPoint(), QPoint(0, 2 * 120), Qt::NoButton,
                          Qt::NoModifier, Qt::NoScrollPhase, false);
        QApplication::sendEvent(view_, &wheel);
        // Two notches in: 2^(-1/2) of the scale, the point under the cursor fixed.
        QVERIFY(std::abs(view_->scale() / scale - std::pow(2.0, -0.5)) < 1e-12);
        const QPointF after = view_->widgetToLatent(at);
        QVERIFY(std::abs(after.x() - before.x()) < 1e-12 && std::abs(after.y() - before.y()) < 1e-12);
        waitForMap();
    }

    void dragPans() {
        const QPoint a(view_->width() / 2, view_->height() / 2), b = a + QPoint(40, -25);
        const QPointF grabbed = view_->widgetToLatent(a);
        const double scale = view_->scale();
        QSignalSpy marker(view_, &AtlasMapView::markerChanged);
        QTest::mousePress(view_, Qt::LeftButton, Qt::NoModifier, a);
        for (int k = 1; k <= 4; ++k) {
            const QPointF p = a + (b - a) * (k / 4.0);
            QMouseEvent move(QEvent::MouseMove, p, view_->mapToGlobal(p.toPoint()), Qt::NoButton,
                             Qt::LeftButton, Qt::NoModifier);
            QApplication::sendEvent(view_, &move);
        }
        QTest::mouseRelease(view_, Qt::LeftButton, Qt::NoModifier, b);
        // The latent point grabbed is now under the mouse; no zoom, no marker.
        const QPointF now = view_->widgetToLatent(b);
        QVERIFY(std::abs(now.x() - grabbed.x()) < 1e-12 && std::abs(now.y() - grabbed.y()) < 1e-12);
        QCOMPARE(view_->scale(), scale);
        QVERIFY(!view_->hasMarker());
        QCOMPARE(marker.count(), 0);
        waitForMap();
    }

    // Every zoom and pan is followed at once by a preview of the new window
    // (the library's preview at a sixth of the side: from the field held
    // for it, else 64 samples a pixel), then by the full map once the
    // motion stops; both are the library's own maps of that window, pixel
    // for pixel. Prints how long after the gesture each frame was drawn.
    void previewFollowsTheMotionThenTheFullMap() {
        struct Frame {
            int level;
            double ms;
            QImage image;
            BrdfAtlasView window;
        };
        QVector<Frame> frames;
        const QMetaObject::Connection c =
            connect(view_, &AtlasMapView::frameShown, [&](int level, double ms) {
                frames << Frame{level, ms, view_->mapImage(), view_->mapWindow()};
            });
        const brdf_atlas::Model m(modelPath_.toStdString());
        const QSize full(view_->mapImage().size());
        const QSize preview((full.width() + AtlasMapView::kPreviewDivisor - 1) / AtlasMapView::kPreviewDivisor,
                            (full.height() + AtlasMapView::kPreviewDivisor - 1) / AtlasMapView::kPreviewDivisor);
        auto check = [&](const char *gesture) {
            waitForMap();
            QVERIFY2(frames.size() >= 2, gesture);
            const Frame &first = frames.first(), &last = frames.last();
            QCOMPARE(first.level, AtlasMapView::kPreview);
            QCOMPARE(first.image.size(), preview);
            // The panel's own model's preview (what it holds is what its
            // earlier maps built; a preview builds nothing).
            const brdf_atlas::Model &own = *view_->model();
            QVERIFY2(sameAsLibraryMap(own, first.image, first.window, AtlasMapView::kPreviewSamples, true),
                     gesture);
            // Every window here lies inside the fields `fit` saved: the
            // preview is drawn from them, not from 64 samples a pixel.
            QVERIFY2(!sameAsLibraryMap(own, first.image, first.window, AtlasMapView::kPreviewSamples),
                     gesture);
            QCOMPARE(last.level, AtlasMapView::kFull);
            QCOMPARE(last.image.size(), full);
            QVERIFY2(sameAsLibraryMap(m, last.image, last.window, 0), gesture);
            const BrdfAtlasView w = view_->window();
            QVERIFY(last.window.x0 == w.x0 && last.window.y1 == w.y1);
            QCOMPARE(view_->frameLatencyMs(AtlasMapView::kFull), last.ms);
            qInfo("%s: %dx%d preview drawn %.1f ms after the last move, %dx%d map %.1f ms after",
                  gesture, first.image.width(), first.image.height(), first.ms, last.image.width(),
                  last.image.height(), last.ms);
        };
        // A wheel notch out, about the centre.
        const QPointF at(view_->width() / 2.0, view_->height() / 2.0);
        QWheelEvent wheel(at, view_->mapToGlobal(at.toPoint()), QPoint(), QPoint(0, -120), Qt::NoButton,
                          Qt::NoModifier, Qt::NoScrollPhase, false);
        QApplication::sendEvent(view_, &wheel);
        check("zoom");
        // A drag of twelve moves, the events handled between them as a user's
        // would be: previews follow the motion, a full map only at the end.
        frames.clear();
        const QPoint a(view_->width() / 2, view_->height() / 2);
        QTest::mousePress(view_, Qt::LeftButton, Qt::NoModifier, a);
        for (int k = 1; k <= 12; ++k) {
            const QPointF p = a + QPointF(3.0 * k, -2.0 * k);
            QMouseEvent move(QEvent::MouseMove, p, view_->mapToGlobal(p.toPoint()), Qt::NoButton,
                             Qt::LeftButton, Qt::NoModifier);
            QApplication::sendEvent(view_, &move);
            QTest::qWait(15);
        }
        QTest::mouseRelease(view_, Qt::LeftButton, Qt::NoModifier, a + QPoint(36, -24));
        check("pan");
        for (int k = 0; k + 1 < frames.size(); ++k) QCOMPARE(frames[k].level, AtlasMapView::kPreview);
        // Back where it was.
        frames.clear();
        QTest::mousePress(view_, Qt::LeftButton, Qt::NoModifier, a + QPoint(36, -24));
        QMouseEvent back(QEvent::MouseMove, QPointF(a), view_->mapToGlobal(a), Qt::NoButton, Qt::LeftButton,
                         Qt::NoModifier);
        QApplication::sendEvent(view_, &back);
        QTest::mouseRelease(view_, Qt::LeftButton, Qt::NoModifier, a);
        QWheelEvent in(at, view_->mapToGlobal(at.toPoint()), QPoint(), QPoint(0, 120), Qt::NoButton,
                       Qt::NoModifier, Qt::NoScrollPhase, false);
        QApplication::sendEvent(view_, &in);
        waitForMap();
        disconnect(c);
    }

    void clickSetsTheMarker() {
        QVERIFY(!panel_->validateButton()->isEnabled() && !panel_->exportButton()->isEnabled());
        // Between two materials: half-way from the first to the second,
        // brought into view if the zooms and pans before left it outside
        // (with a model of many materials the two may lie far apart).
        const QPointF mid = (view_->materialPoints()[0] + view_->materialPoints()[1]) / 2;
        // Zoomed in until no material's point is within two hit radii of the
        // midpoint (a click there would pick that material).
        double scale = view_->scale();
        auto clear = [this, &mid](double s) {
            for (const QPointF &p : view_->materialPoints()) {
                if (std::hypot(p.x() - mid.x(), p.y() - mid.y()) / s <= 2 * AtlasMapView::kHitRadius) return false;
            }
            return true;
        };
        while (!clear(scale)) scale /= 2;
        if (scale != view_->scale() || !view_->rect().contains(view_->latentToWidget(mid).toPoint())) {
            view_->setWindow(mid, scale);
            waitForMap();
        }
        const QPoint at = view_->latentToWidget(mid).toPoint();
        QVERIFY(view_->rect().contains(at));
        const QPointF expected = view_->widgetToLatent(at);
        QSignalSpy marker(view_, &AtlasMapView::markerChanged);
        QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier, at);
        QCOMPARE(marker.count(), 1);
        QVERIFY(view_->hasMarker());
        QCOMPARE(view_->marker(), expected);
        QCOMPARE(marker.first()[0].toDouble(), expected.x());
        const QString text = panel_->coordinatesLabel()->text();
        QVERIFY2(text.contains(QString::number(expected.x(), 'f', 4)) &&
                     text.contains(QString::number(expected.y(), 'f', 4)),
                 qPrintable(text));
        QVERIFY(panel_->validateButton()->isEnabled() && panel_->exportButton()->isEnabled());
    }

    void validateReconstructsOffTheGuiThread() {
        // No rule chosen yet: the library's default, the material the map draws.
        QCOMPARE(panel_->blendRule(), BRDF_ATLAS_BLEND_FLOOR);
        QSignalSpy done(panel_, &AtlasPanel::reconstructed);
        QSignalSpy failed(panel_, &AtlasPanel::failed);
        const QPointF m = view_->marker();
        QTest::mouseClick(panel_->validateButton(), Qt::LeftButton);
        // The click returned before the result: it is delivered by the event
        // loop from a worker thread, and the busy indicator shows meanwhile.
        QCOMPARE(done.count(), 0);
        QVERIFY(panel_->busy());
        // The plausibility comes with the table, from the same worker.
        QVERIFY(!panel_->plausibilityLabel()->isEnabled());
        QVERIFY(panel_->plausibilityLabel()->text().contains("checking"));
        QVERIFY(panel_->progressBar()->isVisibleTo(panel_));
        QVERIFY(!panel_->validateButton()->isEnabled());
        QTRY_VERIFY_WITH_TIMEOUT(done.count() + failed.count() > 0, 120000);
        QVERIFY2(failed.isEmpty(), failed.isEmpty() ? "" : qPrintable(failed.first().first().toString()));
        QVERIFY(!panel_->progressBar()->isVisibleTo(panel_));
        const AtlasReconstruction r = done.first().first().value<AtlasReconstruction>();
        QCOMPARE(r.x, m.x());
        QCOMPARE(r.y, m.y());
        QCOMPARE(r.blend, BRDF_ATLAS_BLEND_FLOOR);
        // The default rule goes unnamed in the status line.
        QVERIFY2(panel_->statusLabel()->text().contains(": reconstructed in "),
                 qPrintable(panel_->statusLabel()->text()));
        QVERIFY(r.name.contains(view_->materialNames()[view_->nearestMaterial(m)]));
        QVERIFY(r.table);
        const std::vector<double> want = referenceTable(modelPath_, m.x(), m.y());
        QCOMPARE(r.table->size(), want.size());
        QCOMPARE(r.table->size(), 3 * r.dims.theta_h * r.dims.theta_d * r.dims.phi_d);
        QVERIFY2(std::memcmp(r.table->data(), want.data(), want.size() * sizeof(double)) == 0,
                 "the widget's table differs from brdf_atlas_model_reconstruct's");
        // Not a trivial table: values vary and some are measured.
        int positive = 0;
        for (double v : want) positive += v > 0;
        QVERIFY(positive > int(want.size() / 4));
    }

    void plausibilityIsShownUnderValidate() {
        const QString error = validateBetweenMaterials(panel_);
        QVERIFY2(error.isEmpty(), qPrintable(error));
        checkPlausibilityShown(modelPath_, panel_);
    }

    void steppedRuleIsValidatedWhenChosen() {
        // A point where the stepped rule moves the GP's weights, so that its
        // table differs from the GP's and from the default floor's: beyond
        // one material, away from another.
        const QVector<QPointF> pts = view_->materialPoints();
        QPointF at;
        bool found = false;
        for (int i = 0; i < pts.size() && !found; ++i) {
            for (int j = 0; j < pts.size() && !found; ++j) {
                if (i == j) continue;
                at = pts[i] + 0.5 * (pts[i] - pts[j]);
                const std::vector<double> stepped =
                    referenceTable(modelPath_, at.x(), at.y(), BRDF_ATLAS_BLEND_PLAUSIBLE);
                found = stepped != referenceTable(modelPath_, at.x(), at.y(), BRDF_ATLAS_BLEND_GP) &&
                        stepped != referenceTable(modelPath_, at.x(), at.y());
            }
        }
        QVERIFY2(found, "no point of the test model where the stepped rule moves the weights");
        view_->setMarker(at);
        chooseBlend(panel_, "Stepped");
        const QString error = validateAtMarker(panel_);
        chooseBlend(panel_, "Soft floor");
        QVERIFY2(error.isEmpty(), qPrintable(error));
        const AtlasReconstruction &r = panel_->lastReconstruction();
        QCOMPARE(r.blend, BRDF_ATLAS_BLEND_PLAUSIBLE);
        QVERIFY(*r.table == referenceTable(modelPath_, at.x(), at.y(), BRDF_ATLAS_BLEND_PLAUSIBLE));
        checkPlausibilityShown(modelPath_, panel_, BRDF_ATLAS_BLEND_PLAUSIBLE);
        QVERIFY2(panel_->statusLabel()->text().contains("(stepped plausible rule)"),
                 qPrintable(panel_->statusLabel()->text()));
    }

    void blendChoiceIsRemembered() {
        // By the rule's name; a new panel starts with the last choice, and
        // with the default for a name this version does not know.
        auto stored = [] { return QSettings("brdf-atlas", "plugin").value(AtlasPanel::blendKey()).toString(); };
        const struct { const char *label, *key; std::int32_t rule; } choices[] = {
            {"GP", "gp", BRDF_ATLAS_BLEND_GP}, {"Stepped", "plausible", BRDF_ATLAS_BLEND_PLAUSIBLE},
            {"Soft floor", "floor", BRDF_ATLAS_BLEND_FLOOR}};
        for (const auto &c : choices) {
            chooseBlend(panel_, c.label);
            QCOMPARE(stored(), QString(c.key));
            AtlasPanel next;
            QCOMPARE(next.blendBox()->currentText(), QString(c.label));
            QCOMPARE(next.blendRule(), c.rule);
        }
        QSettings("brdf-atlas", "plugin").setValue(AtlasPanel::blendKey(), "convex");
        QCOMPARE(AtlasPanel().blendRule(), BRDF_ATLAS_BLEND_FLOOR);
        // Each rule's tooltip says that the map draws the soft floor's material.
        for (int i = 0; i < panel_->blendBox()->count(); ++i) {
            const QString tip = panel_->blendBox()->itemData(i, Qt::ToolTipRole).toString();
            QVERIFY2(tip.contains("the map draws", Qt::CaseInsensitive) && (i == 0 || tip.contains("soft floor")),
                     qPrintable(tip));
        }
    }

    void plausibilityWording() {
        // The words for numbers made up to reach each branch (the library's
        // own numbers are checked against the panel below and above).
        QCOMPARE(atlasPercentText(0), QStringLiteral("0%"));
        QCOMPARE(atlasPercentText(2e-7), QStringLiteral("under 0.001%"));
        QCOMPARE(atlasPercentText(2.3e-5), QStringLiteral("0.0023%"));
        QCOMPARE(atlasPercentText(0.031), QStringLiteral("3.1%"));
        QCOMPARE(atlasPercentText(0.254), QStringLiteral("25%"));
        // clamped_reflectance, clamped_values, max_albedo, max_albedo_incidence,
        // variance, weight_sum, plausible, low_confidence
        const BrdfAtlasPlausibility fine{2.3e-5, 1e-3, 0.834, 60, 0.01, 1.0, 1, 0};
        QCOMPARE(atlasPlausibilityText(fine),
                 QString("Plausible: 0.0023% of the reflectance clamped, largest albedo 0.83 (at 60") +
                     QChar(0x00B0) + ").");
        QVERIFY(atlasPlausibilityStyle(fine).isEmpty());
        const BrdfAtlasPlausibility negative{0.031, 0.2, 0.9, 80, 0.7, 0.4, 0, 1};
        QString text = atlasPlausibilityText(negative);
        QVERIFY2(text.startsWith("Not plausible: 3.1% of the reflectance is negative (clamped to 0); "
                                 "largest albedo 0.90 (at 80") &&
                     text.endsWith(" The model knows little here (variance 0.70 of 1)."),
                 qPrintable(text));
        QVERIFY(atlasPlausibilityStyle(negative).contains("c03030"));
        // Just above 1: as many digits as it takes not to read as 1.00.
        const BrdfAtlasPlausibility bright{0, 0, 1.004, 88, 0.1, 1.0, 0, 0};
        text = atlasPlausibilityText(bright);
        QVERIFY2(text.startsWith("Not plausible: largest albedo 1.004 at 88") &&
                     text.endsWith(", above 1 (more light out than in); none of the reflectance clamped to 0."),
                 qPrintable(text));
    }

    void markerWords() {
        // A marker the model does not give back, one it does, and no marker.
        using Marker = brdf_atlas::Model::Marker;
        QCOMPARE(atlasMarkerText("black-fabric", Marker{3, 6.2, 7.2}),
                 QStringLiteral("Not black-fabric: the model gives back 7.2x its albedo at its "
                                "marker (worst channel, 620% off)."));
        QCOMPARE(atlasMarkerText("alumina-oxide", Marker{0, 0.29, 0.71}),
                 QStringLiteral("Not alumina-oxide: the model gives back 0.71x its albedo at its "
                                "marker (worst channel, 29% off)."));
        QVERIFY(atlasMarkerText("gold", Marker{1, 0.004, 1.004}).isEmpty());
        QVERIFY(atlasMarkerText("-", Marker{SIZE_MAX, 0, 0}).isEmpty());
        // The library's own answer at each material of the test's model: the
        // default fit gives every one back.
        std::shared_ptr<const brdf_atlas::Model> model = panel_->mapView()->model();
        QVERIFY(model);
        for (std::size_t i = 0; i < model->material_count(); ++i) {
            const auto p = model->latent_point(i);
            const Marker m = model->marker(p[0], p[1]);
            QCOMPARE(m.material, i);
            QVERIFY2(m.given_back(), qPrintable(QString::number(m.albedo_error)));
        }
    }

    void screenshot() {
        const QString dir = qEnvironmentVariable("BRDF_ATLAS_ARTEFACTS", ".");
        QDir().mkpath(dir);
        const QString path = QDir(dir).filePath("atlas-widget.png");
        waitForMap();  // the panel may have been resized by the texts since
        const QImage shot = panel_->grab().toImage();
        QVERIFY(shot.save(path));
        QVERIFY(QImage(path).size() == shot.size());
        qInfo("screenshot: %s", qPrintable(path));
    }

    void plausibilityIsGreyedElsewhere() {
        const QPointF validated = view_->marker();
        const QString text = panel_->plausibilityLabel()->text();
        // The marker elsewhere: the line no longer speaks of that material.
        QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier,
                          view_->latentToWidget(view_->materialPoints()[2]).toPoint());
        QVERIFY(view_->marker() != validated);
        QVERIFY(!panel_->plausibilityLabel()->isEnabled());
        QVERIFY2(!panel_->plausibilityLabel()->text().contains("lausible:"),
                 qPrintable(panel_->plausibilityLabel()->text()));
        QVERIFY(panel_->plausibilityLabel()->styleSheet().isEmpty());
        // Back on the validated point: its verdict again.
        view_->setMarker(validated);
        QVERIFY(panel_->plausibilityLabel()->isEnabled());
        QCOMPARE(panel_->plausibilityLabel()->text(), text);
    }

    void implausibleMaterialIsSaidInRed() {
        // The first point of a grid over the model's default view, widened
        // twice, where the library says the GP's material is not plausible
        // (mixed-sign weights between unlike materials, or far from them),
        // validated with "GP" chosen: the default floor's never clamps.
        brdf_atlas::Model m(modelPath_.toStdString());
        const brdf_atlas::View v = m.view();
        const double cx = (v.x0 + v.x1) / 2, cy = (v.y0 + v.y1) / 2;
        const double hw = v.x1 - v.x0, hh = v.y1 - v.y0;
        const int steps = 8;
        bool found = false;
        QPointF at;
        for (int j = 0; j <= steps && !found; ++j) {
            for (int i = 0; i <= steps && !found; ++i) {
                at = QPointF(cx - hw + 2 * hw * i / steps, cy - hh + 2 * hh * j / steps);
                found = m.plausibility(at.x(), at.y(), BRDF_ATLAS_BLEND_GP).plausible == 0;
            }
        }
        if (!found) QSKIP("the library finds every GP material of the grid plausible on this model");
        view_->setMarker(at);
        QVERIFY(!panel_->plausibilityLabel()->isEnabled());
        chooseBlend(panel_, "GP");
        const QString error = validateAtMarker(panel_);
        chooseBlend(panel_, "Soft floor");
        QVERIFY2(error.isEmpty(), qPrintable(error));
        // The GP's table, not the default floor's, which differs there.
        const AtlasReconstruction &r = panel_->lastReconstruction();
        QCOMPARE(r.blend, BRDF_ATLAS_BLEND_GP);
        const std::vector<double> gp = referenceTable(modelPath_, at.x(), at.y(), BRDF_ATLAS_BLEND_GP);
        QVERIFY2(*r.table == gp, "the widget's GP table differs from brdf_atlas_model_reconstruct_with's");
        QVERIFY2(gp != referenceTable(modelPath_, at.x(), at.y()), "the GP's table is the default floor's");
        QVERIFY2(panel_->statusLabel()->text().contains("(GP blend)"), qPrintable(panel_->statusLabel()->text()));
        checkPlausibilityShown(modelPath_, panel_, BRDF_ATLAS_BLEND_GP);
        QLabel *label = panel_->plausibilityLabel();
        QVERIFY2(label->text().startsWith("Not plausible: "), qPrintable(label->text()));
        // Squeezed to its minimum size, the panel still shows every text
        // whole: each label as tall as its wrapped text, no two widgets
        // overlapping. A screenshot of that beside the first.
        const QSize size = panel_->size();
        panel_->resize(1, 1);  // a window stops at its minimum size
        // The labels' minimum heights follow the narrower width, the layout's
        // minimum follows them, and the window that: wait until it settles.
        auto settled = [this] {
            const QSize min = panel_->layout()->totalMinimumSize();
            return panel_->minimumSize() == min && panel_->size() == min;
        };
        QTRY_VERIFY_WITH_TIMEOUT(settled(), 10000);
        const QString path =
            QDir(qEnvironmentVariable("BRDF_ATLAS_ARTEFACTS", ".")).filePath("atlas-widget-minimum.png");
        QVERIFY(panel_->grab().toImage().save(path));
        qInfo("screenshot at the minimum size: %s", qPrintable(path));
        QList<QWidget *> shown;
        for (QWidget *w : panel_->findChildren<QWidget *>(QString(), Qt::FindDirectChildrenOnly)) {
            if (w->isVisibleTo(panel_)) shown << w;
        }
        auto where = [](const QWidget *w) {
            const QRect g = w->geometry();
            return QStringLiteral("%1 at %2,%3 %4x%5")
                .arg(w->metaObject()->className())
                .arg(g.x()).arg(g.y()).arg(g.width()).arg(g.height());
        };
        for (QWidget *w : shown) {
            QVERIFY2(panel_->rect().contains(w->geometry()),
                     qPrintable(where(w) + QStringLiteral(" in %1x%2").arg(panel_->width()).arg(panel_->height())));
            if (auto *l = qobject_cast<QLabel *>(w)) {
                QVERIFY2(l->height() >= l->heightForWidth(l->width()), qPrintable(l->text()));
            }
            for (QWidget *o : shown) {
                QVERIFY2(w == o || !w->geometry().intersects(o->geometry()),
                         qPrintable(where(w) + " and " + where(o)));
            }
        }
        panel_->resize(size);
        waitForMap();
    }

    void saveWritesWhatTheLibraryWrites() {
        // The library writes the default rule's material: validate under it.
        const QString error = validateAtMarker(panel_);
        QVERIFY2(error.isEmpty(), qPrintable(error));
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        const AtlasReconstruction &r = panel_->lastReconstruction();
        QCOMPARE(r.blend, BRDF_ATLAS_BLEND_FLOOR);
        const QString ours = dir.filePath("ours.binary"), theirs = dir.filePath("theirs.binary");
        QVERIFY(panel_->saveTo(ours));
        brdf_atlas::Model(modelPath_.toStdString()).save(r.x, r.y, theirs.toStdString());
        const QByteArray a = readAll(ours), b = readAll(theirs);
        QCOMPARE(a.size(), int(12 + r.table->size() * sizeof(double)));
        QVERIFY2(a == b, "the widget's .binary differs from brdf_atlas_model_reconstruct_to_file's");
        // A save into a missing directory fails with a message naming the file.
        QSignalSpy failed(panel_, &AtlasPanel::failed);
        QVERIFY(!panel_->saveTo(dir.filePath("missing/x.binary")));
        QCOMPARE(failed.count(), 1);
        QVERIFY(failed.first().first().toString().contains("missing/x.binary"));
    }

    void exportWritesTheAnalyticFiles() {
        // "Export analytic..." past its directory dialog (exportTo, as saveTo
        // for Save): the fit runs off the GUI thread, the four files appear,
        // and the parameters the panel states are those that
        // brdf_atlas_model_fit_analytic, called directly, fits there.
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        const QPointF m = view_->marker();
        QSignalSpy exported(panel_, &AtlasPanel::exported);
        QSignalSpy failed(panel_, &AtlasPanel::failed);
        panel_->exportTo(dir.path());
        QVERIFY(panel_->busy() && !panel_->exportButton()->isEnabled() && exported.isEmpty());
        QTRY_VERIFY_WITH_TIMEOUT(exported.count() + failed.count() > 0, 120000);
        QVERIFY2(failed.isEmpty(), failed.isEmpty() ? "" : qPrintable(failed.first().first().toString()));
        const AtlasExport &e = panel_->lastExport();
        QVERIFY(e.x == m.x() && e.y == m.y() && panel_->exportButton()->isEnabled());
        const brdf_atlas::Analytic want = brdf_atlas::Model(modelPath_.toStdString()).fit_analytic(m.x(), m.y());
        QVERIFY(std::memcmp(&e.parameters, &want, sizeof want) == 0);
        const QString status = panel_->statusLabel()->text();
        qInfo("export: %s", qPrintable(status));
        auto n = [](double v) { return QString::number(v, 'f', 3); };
        QVERIFY2(status.contains(atlasAnalyticText(want)) && status.contains(e.stem + ".{glb,mtlx,mitsuba.json,fit.json}") &&
                     status.contains(QStringLiteral("base colour (%1, %2, %3)")
                                         .arg(n(want.base_color[0]), n(want.base_color[1]), n(want.base_color[2]))) &&
                     status.contains("roughness " + n(want.roughness)) && status.contains("ior " + n(want.ior)) &&
                     status.contains(QString::number(want.table_error, 'f', 4)),
                 qPrintable(status));
        QCOMPARE(e.files.size(), 4);
        QCOMPARE(QDir(dir.path()).entryList(QDir::Files).size(), 4);
        for (const QString &f : e.files) QVERIFY2(QFileInfo(f).size() > 0, qPrintable(f));
        // The glb's JSON chunk names the material and carries its parameters.
        const QJsonObject material = glbJson(dir.filePath(e.stem + ".glb"))["materials"].toArray()[0].toObject();
        QCOMPARE(material["name"].toString(), e.stem);
        QCOMPARE(material["pbrMetallicRoughness"].toObject()["roughnessFactor"].toDouble(), want.roughness);
        // Into a missing directory: the library's message, in red, naming it.
        panel_->exportTo(dir.filePath("missing"));
        QTRY_VERIFY_WITH_TIMEOUT(failed.count() == 1 && !panel_->busy(), 120000);
        QVERIFY2(failed.first().first().toString().contains("missing: is not a directory"),
                 qPrintable(failed.first().first().toString()));
        QVERIFY(panel_->statusLabel()->styleSheet().contains("c03030"));
    }

    void lowConfidenceIsFadedAndSaid() {
        // Zoomed out far beyond the materials: the map fades where the model
        // knows little, pixel for pixel by the rule, and a click there says so.
        const QPointF centre = view_->centre();
        const double scale = view_->scale();
        view_->setWindow(QPointF(0, 0), 12.0 / view_->width());
        waitForMap();
        const QImage &img = view_->mapImage();
        const BrdfAtlasView w = view_->mapWindow();
        brdf_atlas::Model m(modelPath_.toStdString());
        brdf_atlas::View v{w.x0, w.x1, w.y0, w.y1};
        const brdf_atlas::Model::Map map = m.map(img.width(), img.height(), v);
        const std::vector<float> &rgb = map.rgb, &variance = map.variance;
        // The map's variance (the field's where it is drawn from one) is
        // the exact variance map's within the field's tolerance.
        const std::vector<float> exact = m.variance_map(img.width(), img.height(), v);
        for (std::size_t p = 0; p < exact.size(); ++p) QVERIFY(std::abs(exact[p] - variance[p]) <= 2e-3f);
        int faded = 0;
        for (int y = 0; y < img.height(); ++y) {
            for (int x = 0; x < img.width(); ++x) {
                const std::size_t p = std::size_t(y) * img.width() + x;
                const float *c = &rgb[3 * p];
                // The rule, spelled out: towards linear grey 0.2 by 0.75 (v - 0.5) / 0.5.
                const float t = variance[p] > 0.5f ? 0.75f * std::min(1.0f, (variance[p] - 0.5f) / 0.5f) : 0.0f;
                for (int k = 0; k < 3; ++k) {
                    const float a = std::min(std::max(c[k], 0.0f), 1.0f);
                    const float f = a + t * (0.2f - a);
                    const float e = f <= 0.0031308f ? 12.92f * f : 1.055f * std::pow(f, 1.0f / 2.4f) - 0.055f;
                    const int want = int(std::lround(255 * e));
                    const QRgb got = img.pixel(x, y);
                    const int have = k == 0 ? qRed(got) : k == 1 ? qGreen(got) : qBlue(got);
                    QVERIFY2(std::abs(have - want) <= 1, qPrintable(QStringLiteral("pixel %1,%2").arg(x).arg(y)));
                }
                faded += t > 0;
            }
        }
        QVERIFY2(faded > 0 && faded < img.width() * img.height(), qPrintable(QString::number(faded)));
        // A click in a corner, far from every material.
        QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier, QPoint(3, 3));
        QVERIFY(m.variance(view_->marker().x(), view_->marker().y()) > 0.5);
        QVERIFY2(panel_->statusLabel()->text().contains("the model knows little here", Qt::CaseInsensitive),
                 qPrintable(panel_->statusLabel()->text()));
        // On a material: no such words.
        QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier,
                          view_->latentToWidget(view_->materialPoints()[0]).toPoint());
        QVERIFY2(!panel_->statusLabel()->text().contains("knows little"),
                 qPrintable(panel_->statusLabel()->text()));
        view_->setWindow(centre, scale);
        waitForMap();
    }

    void clickOnAMaterialPicksItExactly() {
        // A click a few pixels off a material's point picks that material's
        // latent point exactly (the nearest point within kHitRadius), so a
        // material in a cluster is picked without zooming in.
        QSignalSpy marker(view_, &AtlasMapView::markerChanged);
        for (int i = 0; i < view_->materialPoints().size(); ++i) {
            const QPointF p = view_->materialPoints()[i];
            if (!view_->rect().adjusted(8, 8, -8, -8).contains(view_->latentToWidget(p).toPoint())) continue;
            const QPoint at = view_->latentToWidget(p).toPoint() + QPoint(3, -2);
            // The expected pick, by brute force over every material.
            int nearest = -1;
            double best = AtlasMapView::kHitRadius;
            for (int j = 0; j < view_->materialPoints().size(); ++j) {
                const QPointF d = view_->latentToWidget(view_->materialPoints()[j]) - QPointF(at);
                const double dist = std::hypot(d.x(), d.y());
                if (dist <= best) {
                    best = dist;
                    nearest = j;
                }
            }
            QVERIFY(nearest >= 0);
            QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier, at);
            QCOMPARE(view_->marker(), view_->materialPoints()[nearest]);
            QCOMPARE(marker.last()[0].toDouble(), view_->materialPoints()[nearest].x());
        }
        QVERIFY(marker.count() > 0);
        // Far from every point: the point under the cursor.
        for (int y = 4; y < view_->height(); y += 9) {
            for (int x = 4; x < view_->width(); x += 9) {
                bool far = true;
                for (const QPointF &p : view_->materialPoints()) {
                    const QPointF d = view_->latentToWidget(p) - QPointF(x, y);
                    far = far && std::hypot(d.x(), d.y()) > 2 * AtlasMapView::kHitRadius;
                }
                if (!far) continue;
                QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier, QPoint(x, y));
                QCOMPARE(view_->marker(), view_->widgetToLatent(QPointF(x, y)));
                return;
            }
        }
        QFAIL("no pixel of the view is far from every material");
    }

    void largerMapIsItsOwnWindow() {
        // "Larger map" moves the same view (window, marker, map) into a
        // window of its own, large and square; a click there is the panel's
        // marker; closing the window brings the map back.
        const QSize inPanel = view_->size();
        QTest::mouseClick(panel_->detachButton(), Qt::LeftButton);
        QVERIFY(panel_->mapDetached());
        QVERIFY(QTest::qWaitForWindowExposed(panel_->mapWindow()));
        QCOMPARE(static_cast<QWidget *>(view_)->window(), panel_->mapWindow());
        QTRY_VERIFY(view_->width() >= 320 && view_->height() >= 320);
        QVERIFY(view_->width() > inPanel.width() || view_->height() > inPanel.height());
        waitForMap();
        const QPoint at(view_->width() / 3, view_->height() / 3);
        QTest::mouseClick(view_, Qt::LeftButton, Qt::NoModifier, at);
        const int i = view_->nearestMaterial(view_->marker());
        QVERIFY(panel_->coordinatesLabel()->text().contains(QString::number(view_->marker().x(), 'f', 4)));
        QVERIFY(i >= 0);
        // A name hovered in the window is not left drawn on the panel's map.
        // (The move is sent to the view itself: QTest::mouseMove places
        // the platform's cursor, which finds the panel's window first.)
        view_->setWindow(view_->materialPoints()[i], view_->scale());
        QMouseEvent move(QEvent::MouseMove, view_->latentToWidget(view_->materialPoints()[i]),
                         Qt::NoButton, Qt::NoButton, Qt::NoModifier);
        QApplication::sendEvent(view_, &move);
        QCOMPARE(view_->hoveredMaterial(), i);
        QVERIFY(panel_->mapWindow()->close());
        QCOMPARE(view_->hoveredMaterial(), -1);
        QVERIFY(!panel_->mapDetached());
        QVERIFY(!panel_->detachButton()->isChecked());
        QCOMPARE(static_cast<QWidget *>(view_)->window(), static_cast<QWidget *>(panel_));
        QVERIFY(view_->isVisible() && !panel_->mapWindow()->isVisible());
        QTRY_COMPARE(view_->size(), inPanel);
        waitForMap();
    }

    void openFailuresAreShownNamingTheFile() {
        // Each way a model fails to open: the panel's status line (red) and
        // the failed signal carry one message naming the file at fault and
        // what is wrong with it; no model is shown.
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        const QString name = QFileInfo(modelPath_).fileName();
        auto copyModel = [&](const QString &sub) {
            QDir(dir.path()).mkpath(sub);
            const QString m = dir.filePath(sub + "/" + name);
            if (!QFile::copy(modelPath_, m)) qFatal("cannot copy the model");
            return m;
        };
        const QString missing = dir.filePath("missing.atlas");
        const QString text = dir.filePath("notes.atlas");
        rewriteInPlace(text, "these are notes, not a model\n");
        const QString noStore = copyModel("nostore");
        const QString shortStore = copyModel("short");
        QVERIFY(QFile::copy(modelPath_ + ".store", shortStore + ".store"));
        QVERIFY(QFile::resize(shortStore + ".store", 100));
        struct Case {
            QString path, culprit, what;
        };
        const QList<Case> cases = {
            {missing, "missing.atlas", "No such file"},
            {text, "notes.atlas", "not"},
            {noStore, name + ".store", "No such file"},
            {shortStore, name + ".store", ""},
        };
        for (const Case &c : cases) {
            AtlasPanel panel;
            panel.resize(360, 460);
            panel.show();
            QSignalSpy opened(&panel, &AtlasPanel::modelOpened);
            QSignalSpy failed(&panel, &AtlasPanel::failed);
            panel.openModel(c.path);
            QTRY_VERIFY_WITH_TIMEOUT(failed.count() + opened.count() > 0 && !panel.busy(), 60000);
            QCOMPARE(opened.count(), 0);
            const QString message = failed.first().first().toString();
            QVERIFY2(message.contains(c.culprit) && message.contains(c.what), qPrintable(message));
            QCOMPARE(panel.statusLabel()->text(), message);
            QVERIFY(panel.statusLabel()->styleSheet().contains("c03030"));
            QVERIFY(!panel.mapView()->model());
        }
    }

    void aModelWithoutFieldsGetsThemBuiltAndSaved() {
        // A copy of the model without its saved fields (as from a library
        // fit, or an older version's).
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        // Same names: the model names its store.
        const QString model = dir.filePath(QFileInfo(modelPath_).fileName());
        QVERIFY(QFile::copy(modelPath_, model));
        QVERIFY(QFile::copy(modelPath_ + QStringLiteral(".store"), model + QStringLiteral(".store")));
        // MODEL.fields: the model's name with its last extension replaced.
        const QString fields =
            dir.filePath(QFileInfo(model).completeBaseName() + QStringLiteral(".fields"));
        QVERIFY(!QFile::exists(fields));
        QCOMPARE(brdf_atlas::Model(model.toStdString()).saved_fields(), std::size_t(0));

        AtlasPanel panel;
        panel.resize(360, 460);
        panel.show();
        QVERIFY(QTest::qWaitForWindowExposed(&panel));
        QSignalSpy opened(&panel, &AtlasPanel::modelOpened);
        panel.openModel(model);
        // Built off the GUI thread, the busy bar showing, then saved.
        QTRY_VERIFY_WITH_TIMEOUT(opened.count() == 1 && !panel.busy(), 120000);
        QVERIFY2(QFile::exists(fields), qPrintable(panel.statusLabel()->text()));
        QVERIFY(brdf_atlas::Model(model.toStdString()).saved_fields() >= 2);
        // (The job's end reaches the panel through the event loop.)
        QTRY_COMPARE_WITH_TIMEOUT(panel.statusLabel()->text(), QStringLiteral("Click the map, then Validate."),
                                  10000);
        QTRY_VERIFY_WITH_TIMEOUT(!panel.mapView()->mapPending() && !panel.mapView()->mapImage().isNull(), 60000);
        // The panel's map is then the library's, drawn from those fields.
        const brdf_atlas::Model fresh(model.toStdString());
        QVERIFY(sameAsLibraryMap(fresh, panel.mapView()->mapImage(), panel.mapView()->mapWindow(), 0));

        // A second panel on the same model finds them: nothing built again.
        const QDateTime written = QFileInfo(fields).lastModified();
        AtlasPanel again;
        again.show();
        QSignalSpy reopened(&again, &AtlasPanel::modelOpened);
        again.openModel(model);
        QTRY_VERIFY_WITH_TIMEOUT(reopened.count() == 1, 60000);
        QVERIFY(!again.busy());
        QCOMPARE(QFileInfo(fields).lastModified(), written);
    }

    void storeRewrittenWhileOpenIsShownAndRecovered() {
        // A copy of the model, so that the first panel's stays as it is.
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        const QString model = dir.filePath(QFileInfo(modelPath_).fileName());
        const QString store = model + QStringLiteral(".store");
        QVERIFY(QFile::copy(modelPath_, model));
        QVERIFY(QFile::copy(modelPath_ + QStringLiteral(".store"), store));
        const QByteArray original = readAll(store);

        AtlasPanel panel;
        panel.resize(360, 460);
        panel.show();
        QVERIFY(QTest::qWaitForWindowExposed(&panel));
        QSignalSpy opened(&panel, &AtlasPanel::modelOpened);
        panel.openModel(model);
        QTRY_VERIFY_WITH_TIMEOUT(opened.count() == 1 && !panel.busy(), 60000);
        QTRY_VERIFY_WITH_TIMEOUT(!panel.mapView()->mapPending() && !panel.mapView()->mapImage().isNull(), 60000);
        QString error = validateBetweenMaterials(&panel);
        QVERIFY2(error.isEmpty(), qPrintable(error));
        const AtlasReconstruction before = panel.lastReconstruction();
        QVERIFY(before.table);
        const std::vector<double> kept = *before.table;

        // Rewritten shorter, in place, while the model is open.
        rewriteInPlace(store, original.left(original.size() / 2));
        error = validateBetweenMaterials(&panel);
        QVERIFY2(error.contains(QStringLiteral("changed on disk while open")) &&
                     error.contains(QFileInfo(store).fileName()),
                 qPrintable(error));
        // The panel shows it, and stays usable.
        QCOMPARE(panel.statusLabel()->text(), error);
        QVERIFY(!panel.busy());
        QVERIFY(panel.validateButton()->isEnabled());
        // The map of a new window says the same, on the map.
        QSignalSpy mapReady(panel.mapView(), &AtlasMapView::mapReady);
        const QPointF at(panel.mapView()->width() / 2.0, panel.mapView()->height() / 2.0);
        QWheelEvent wheel(at, panel.mapView()->mapToGlobal(at.toPoint()), QPoint(), QPoint(0, 120),
                          Qt::NoButton, Qt::NoModifier, Qt::NoScrollPhase, false);
        QApplication::sendEvent(panel.mapView(), &wheel);
        QTRY_VERIFY_WITH_TIMEOUT(!mapReady.isEmpty() && !panel.mapView()->mapPending(), 60000);
        QVERIFY2(mapReady.last().first().toString().contains(QStringLiteral("changed on disk while open")),
                 qPrintable(mapReady.last().first().toString()));
        // What was reconstructed before is untouched and still saves.
        QCOMPARE(*panel.lastReconstruction().table, kept);
        QVERIFY(panel.saveTo(dir.filePath(QStringLiteral("kept.binary"))));
        QCOMPARE(readAll(dir.filePath(QStringLiteral("kept.binary"))).size(),
                 int(12 + kept.size() * sizeof(double)));
        // The first panel, on its own model, still answers.
        QCOMPARE(validateBetweenMaterials(panel_), QString());

        // The store restored and the model reopened: Validate works again.
        rewriteInPlace(store, original);
        panel.openModel(model);
        QTRY_VERIFY_WITH_TIMEOUT(opened.count() == 2 && !panel.busy(), 60000);
        error = validateBetweenMaterials(&panel);
        QVERIFY2(error.isEmpty(), qPrintable(error));
        const AtlasReconstruction &after = panel.lastReconstruction();
        QVERIFY(*after.table == referenceTable(model, after.x, after.y));
    }
};

QTEST_MAIN(TestAtlasMap)
#include "tst_atlasmap.moc"
