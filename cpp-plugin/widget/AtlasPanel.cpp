// AtlasPanel.cpp: AtlasPanel, the map view with the marker's coordinates,
// the blend rule, Validate, the plausibility line, Export analytic and the
// status line (see AtlasMapWidget.h; its files are in AtlasFiles.cpp).
#include "AtlasMapWidget.h"
#include "AtlasStatus.h"

#include <QComboBox>
#include <QDir>
#include <QEvent>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QLabel>
#include <QProgressBar>
#include <QPushButton>
#include <QScrollArea>
#include <QSettings>
#include <QVBoxLayout>
#include <QtConcurrent/QtConcurrentRun>

#include <algorithm>
#include <exception>

namespace {

// As in AtlasMapWidget.cpp: the library's message, as the panel shows it.
QString errorText(const std::exception &e) { return QString::fromUtf8(e.what()); }

// The status line while the map's fields are built for a model without them.
const QString kBuildingFields =
    QStringLiteral("building the map's fields (once: saved beside the model)...");

}  // namespace

AtlasPanel::AtlasPanel(QWidget *parent)
    : QWidget(parent),
      view_(new AtlasMapView),
      title_(new QLabel),
      coords_(new QLabel),
      validate_(new QPushButton(QStringLiteral("Validate"))),
      save_(new QPushButton(QStringLiteral("Save .binary..."))),
      export_(new QPushButton(QStringLiteral("Export analytic..."))),
      detach_(new QPushButton(QStringLiteral("Larger map"))),
      mapWindow_(new QWidget(this, Qt::Window)),
      mapAway_(new QLabel(QStringLiteral("The map is in its own window: close it to bring the map back."))),
      blendLabel_(new QLabel(QStringLiteral("Blend:"))),
      blend_(new QComboBox),
      plausibility_(new QLabel),
      progress_(new QProgressBar),
      status_(new QLabel),
      details_(new QScrollArea),
      openWatcher_(new QFutureWatcher<Opened>(this)),
      buildWatcher_(new QFutureWatcher<Built>(this)),
      exportWatcher_(new QFutureWatcher<AtlasExport>(this)),
      fieldsWatcher_(new QFutureWatcher<QString>(this)) {
    qRegisterMetaType<AtlasReconstruction>();
    qRegisterMetaType<AtlasExport>();
    setObjectName(QStringLiteral("brdfAtlasPanel"));
    auto *layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    title_->setWordWrap(true);
    // Long texts wrap rather than widen the panel (BRDF Explorer's is 300 px).
    for (QLabel *l : {title_, coords_, plausibility_, status_}) l->setMinimumWidth(1);
    title_->setText(QStringLiteral("brdf-atlas: no model open"));
    layout->addWidget(title_);
    layout->addWidget(view_, 1);
    coords_->setTextInteractionFlags(Qt::TextSelectableByMouse);
    coords_->setWordWrap(true);
    // The blend rule on a row of its own above the buttons: beside them it
    // would widen the panel past BRDF Explorer's parameter window.
    auto *rule = new QHBoxLayout;
    // The rule chosen last time; a name this version does not know, or none,
    // is the default.
    const QString chosen =
        QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin")).value(blendKey()).toString();
    for (const AtlasBlendChoice &c : atlasBlendChoices()) {
        blend_->addItem(c.label, int(c.rule));
        blend_->setItemData(blend_->count() - 1, c.tip, Qt::ToolTipRole);
        if (chosen == c.key) blend_->setCurrentIndex(blend_->count() - 1);
    }
    blend_->setToolTip(atlasBlendChoice(blendRule()).tip);
    blendLabel_->setBuddy(blend_);
    blendLabel_->setToolTip(QStringLiteral("The blend rule Validate makes the material with"));
    rule->addWidget(blendLabel_);
    rule->addWidget(blend_);
    rule->addStretch(1);
    layout->addLayout(rule);
    auto *buttons = new QHBoxLayout;
    validate_->setToolTip(QStringLiteral("Reconstruct the material at the marker"));
    save_->setToolTip(QStringLiteral("Save the last reconstructed material as a MERL .binary file"));
    buttons->addWidget(validate_);
    buttons->addWidget(save_);
    layout->addLayout(buttons);
    // On a row of its own: beside the others it would widen the panel.
    auto *files = new QHBoxLayout;
    export_->setToolTip(
        QStringLiteral("Fit glTF parameters (base colour, metallic, roughness, specular, ior) to the "
                       "soft floor's material at the marker and write it as glTF (.glb), MaterialX "
                       "(.mtlx) and Mitsuba 3 (.mitsuba.json) files with the fit's record (.fit.json) "
                       "into a directory"));
    files->addWidget(export_);
    detach_->setCheckable(true);
    detach_->setToolTip(QStringLiteral("Show the map in a window of its own, as large as you make it"));
    files->addWidget(detach_);
    files->addStretch(1);
    mapWindow_->setWindowTitle(QStringLiteral("brdf-atlas map"));
    mapWindow_->setObjectName(QStringLiteral("brdfAtlasMapWindow"));
    auto *windowLayout = new QVBoxLayout(mapWindow_);
    windowLayout->setContentsMargins(0, 0, 0, 0);
    mapWindow_->installEventFilter(this);
    mapAway_->setWordWrap(true);
    mapAway_->setMinimumWidth(1);
    mapAway_->setAlignment(Qt::AlignCenter);
    mapAway_->setVisible(false);
    layout->addLayout(files);
    plausibility_->setWordWrap(true);
    plausibility_->setTextInteractionFlags(Qt::TextSelectableByMouse);
    plausibility_->setToolTip(
        QStringLiteral("How physical the validated material is: the share of its reflectance that "
                       "came out negative and was clamped to 0 (at most 1% is plausible), and its "
                       "largest directional albedo (at most 1: no more light out than in)"));
    progress_->setRange(0, 0);  // busy indicator: the library reports no fraction
    progress_->setTextVisible(true);
    progress_->setVisible(false);
    status_->setWordWrap(true);
    // The texts that change (the marker's coordinates, the plausibility
    // line, the busy bar, the status line) in a box of fixed height under
    // the buttons, scrolled when they outgrow it: the map's size depends
    // on the panel's alone, so a wrapping status line or the busy bar never
    // shrinks it (nor recomputes it).
    auto *texts = new QWidget;
    auto *column = new QVBoxLayout(texts);
    column->setContentsMargins(0, 0, 0, 0);
    for (QWidget *w : std::initializer_list<QWidget *>{coords_, plausibility_, progress_, status_}) {
        column->addWidget(w);
    }
    column->addStretch(1);
    details_->setObjectName(QStringLiteral("brdfAtlasTexts"));
    details_->setWidget(texts);
    details_->setWidgetResizable(true);
    details_->setFrameShape(QFrame::NoFrame);
    details_->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
    details_->setFixedHeight(kTextLines * fontMetrics().lineSpacing() + 3 * column->spacing());
    layout->addWidget(details_);
    validate_->setEnabled(false);
    save_->setEnabled(false);
    export_->setEnabled(false);
    updateCoordinates();
    showPlausibility();

    connect(view_, &AtlasMapView::markerChanged, this, [this] {
        updateCoordinates();
        sayConfidence();
        showPlausibility();
    });
    connect(validate_, &QPushButton::clicked, this, &AtlasPanel::validatePoint);
    connect(save_, &QPushButton::clicked, this, &AtlasPanel::saveDialog);
    connect(export_, &QPushButton::clicked, this, &AtlasPanel::exportDialog);
    connect(detach_, &QPushButton::toggled, this, &AtlasPanel::setMapDetached);
    connect(blend_, QOverload<int>::of(&QComboBox::currentIndexChanged), this, [this] {
        const AtlasBlendChoice &c = atlasBlendChoice(blendRule());
        blend_->setToolTip(c.tip);
        QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin")).setValue(blendKey(), c.key);
    });
    connect(openWatcher_, &QFutureWatcher<Opened>::finished, this, [this] {
        Opened o = openWatcher_->result();
        setBusy(false, QString());
        if (!o.error.isEmpty()) {
            fail(o.error);
            return;
        }
        modelPath_ = o.path;
        view_->setModel(o.model);
        QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin"))
            .setValue(settingsKey(), QFileInfo(o.path).absoluteFilePath());
        title_->setText(QStringLiteral("brdf-atlas: %1 (%2 materials)")
                            .arg(QFileInfo(o.path).fileName())
                            .arg(view_->materialNames().size()));
        status_->setText(QStringLiteral("Click the map, then Validate."));
        updateCoordinates();
        showPlausibility();
        if (!o.fieldsSaved) prepareFields(o.model);
        emit modelOpened(o.path);
    });
    connect(fieldsWatcher_, &QFutureWatcher<QString>::finished, this, [this] {
        const QString error = fieldsWatcher_->result();
        setBusy(false, QString());
        if (!error.isEmpty()) {
            fail(error);
            return;
        }
        if (status_->text() == kBuildingFields) {
            status_->setText(QStringLiteral("Click the map, then Validate."));
        }
        view_->redraw();
    });
    connect(buildWatcher_, &QFutureWatcher<Built>::finished, this, [this] {
        Built b = buildWatcher_->result();
        const double seconds = clock_.elapsed() / 1000.0;
        setBusy(false, QString());
        if (!b.error.isEmpty()) {
            showPlausibility();
            fail(b.error);
            return;
        }
        last_ = b.r;
        showPlausibility();
        save_->setEnabled(true);
        status_->setStyleSheet(QString());
        status_->setToolTip(QString());
        status_->setText(QStringLiteral("%1: reconstructed%2 in %3 s")
                             .arg(b.r.name)
                             .arg(atlasBlendChoice(b.r.blend).said)
                             .arg(seconds, 0, 'f', 2));
        emit reconstructed(last_);
    });
    connect(exportWatcher_, &QFutureWatcher<AtlasExport>::finished, this, [this] {
        const AtlasExport e = exportWatcher_->result();
        const double seconds = exportClock_.elapsed() / 1000.0;
        setBusy(false, QString());
        if (!e.error.isEmpty()) {
            fail(e.error);
            return;
        }
        exported_ = e;
        status_->setStyleSheet(QString());
        status_->setText(QStringLiteral("%1 Wrote %2.{glb,mtlx,mitsuba.json,fit.json} in %3.")
                             .arg(atlasAnalyticText(e.parameters), e.stem, QDir::toNativeSeparators(e.dir)));
        status_->setToolTip(QStringLiteral("%1 Fitted and written in %2 s.")
                                .arg(atlasAnalyticErrorTip(e.parameters))
                                .arg(seconds, 0, 'f', 1));
        emit exported(e);
    });
}

AtlasPanel::~AtlasPanel() {
    if (fieldsCancel_) fieldsCancel_->store(1);
    fieldsWatcher_->waitForFinished();
    openWatcher_->waitForFinished();
    buildWatcher_->waitForFinished();
    exportWatcher_->waitForFinished();
}

std::int32_t AtlasPanel::blendRule() const { return std::int32_t(blend_->currentData().toInt()); }

bool AtlasPanel::busy() const {
    return openWatcher_->isRunning() || fieldsWatcher_->isRunning() || buildWatcher_->isRunning() ||
           exportWatcher_->isRunning();
}

void AtlasPanel::prepareFields(std::shared_ptr<const brdf_atlas::Model> model) {
    if (fieldsWatcher_->isRunning()) return;
    setBusy(true, kBuildingFields);
    fieldsCancel_ = std::make_shared<std::atomic<std::int32_t>>(0);
    fieldsWatcher_->setFuture(QtConcurrent::run([model, cancel = fieldsCancel_]() -> QString {
        // The fields `brdf-atlas fit` saves: the panel's windows, twice as
        // wide as high, lie inside [-3, 3]^2's.
        try {
            model->prepare_fit_fields(cancel.get());
        } catch (const brdf_atlas::Error &e) {
            if (e.status() == BRDF_ATLAS_STATUS_CANCELLED) return QString();
            return errorText(e);
        } catch (const std::exception &e) {
            return errorText(e);
        }
        return QString();
    }));
}

void AtlasPanel::setBusy(bool busy, const QString &what) {
    // The bar stays while another job runs (a Validate during an export).
    progress_->setVisible(busy || this->busy());
    progress_->setFormat(what);
    if (busy) {
        status_->setStyleSheet(QString());
        status_->setToolTip(QString());
        status_->setText(what);
    }
    updateCoordinates();
}

void AtlasPanel::fail(const QString &message) {
    status_->setStyleSheet(atlasErrorStyle());
    status_->setToolTip(QString());
    status_->setText(message);
    emit failed(message);
}

void AtlasPanel::sayConfidence() {
    std::shared_ptr<const brdf_atlas::Model> model = view_->model();
    if (!model || !view_->hasMarker() || busy()) return;
    const QPointF m = view_->marker();
    try {
        const double v = model->variance(m.x(), m.y());  // no pass over the store
        const brdf_atlas::Model::Marker marker = model->marker(m.x(), m.y());  // nor here
        status_->setStyleSheet(QString());
        status_->setToolTip(QString());
        if (v > BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE) {
            status_->setText(atlasLowConfidenceText(v));
        } else if (!marker.given_back() && marker.material != SIZE_MAX) {
            status_->setStyleSheet(atlasErrorStyle());
            status_->setText(
                atlasMarkerText(view_->materialNames()[int(marker.material)], marker));
        } else {
            status_->setText(QStringLiteral("Click the map, then Validate."));
        }
    } catch (const std::exception &e) {
        fail(errorText(e));
    }
}

void AtlasPanel::showPlausibility() {
    const QPointF m = view_->marker();
    const bool validated = view_->model() && view_->hasMarker() && last_.table &&
                           last_.modelPath == modelPath_ && last_.x == m.x() && last_.y == m.y();
    plausibility_->setEnabled(validated);  // greyed: not about the marker
    plausibility_->setStyleSheet(validated ? atlasPlausibilityStyle(last_.plausibility) : QString());
    if (validated) {
        plausibility_->setText(atlasPlausibilityText(last_.plausibility));
    } else if (!view_->model()) {
        plausibility_->clear();
    } else if (buildWatcher_->isRunning()) {
        plausibility_->setText(QStringLiteral("Plausibility: checking..."));
    } else {
        plausibility_->setText(QStringLiteral("Plausibility: Validate checks the material at the marker."));
    }
}

bool AtlasPanel::mapDetached() const { return detach_->isChecked(); }

void AtlasPanel::setMapDetached(bool detached) {
    if (detach_->isChecked() != detached) {
        detach_->setChecked(detached);  // toggled() calls back with the same value
        return;
    }
    auto *column = static_cast<QVBoxLayout *>(layout());
    // The pointer is not over the view where it goes next.
    view_->clearHover();
    if (detached && view_->parentWidget() != mapWindow_) {
        column->replaceWidget(view_, mapAway_);
        mapAway_->setVisible(true);
        mapWindow_->layout()->addWidget(view_);
        view_->setVisible(true);
        mapWindow_->resize(kDetachedSide, kDetachedSide);
        mapWindow_->show();
        mapWindow_->raise();
    } else if (!detached && view_->parentWidget() == mapWindow_) {
        mapWindow_->layout()->removeWidget(view_);
        column->replaceWidget(mapAway_, view_);
        mapAway_->setVisible(false);
        view_->setVisible(true);
        mapWindow_->hide();
    }
}

bool AtlasPanel::eventFilter(QObject *watched, QEvent *e) {
    if (watched == mapWindow_ && e->type() == QEvent::Close) setMapDetached(false);
    return QWidget::eventFilter(watched, e);
}

bool AtlasPanel::event(QEvent *e) {
    // A new text (a layout request) or a new width changes how many lines a
    // label wraps to. The coordinates and the plausibility keep two lines
    // from the start, so the buttons do not move on a click, nor what is
    // below them on a Validate.
    if (e->type() == QEvent::LayoutRequest || e->type() == QEvent::Resize) {
        const int width = std::max(1, contentsRect().width());
        for (QLabel *l : {title_, status_}) atlasFitLabel(l, width, 1);
        for (QLabel *l : {coords_, plausibility_}) atlasFitLabel(l, width, 2);
    }
    return QWidget::event(e);
}

void AtlasPanel::updateCoordinates() {
    if (view_->hasMarker()) {
        const QPointF m = view_->marker();
        const int near = view_->nearestMaterial(m);
        coords_->setText(QStringLiteral("x = %1, y = %2  (nearest: %3)")
                             .arg(m.x(), 0, 'f', 4)
                             .arg(m.y(), 0, 'f', 4)
                             .arg(near >= 0 ? view_->materialNames()[near] : QStringLiteral("-")));
    } else {
        coords_->setText(view_->model() ? QStringLiteral("x = -, y = -  (click the map)")
                                        : QStringLiteral("x = -, y = -"));
    }
    validate_->setEnabled(view_->model() && view_->hasMarker() && !buildWatcher_->isRunning());
    export_->setEnabled(view_->model() && view_->hasMarker() && !exportWatcher_->isRunning());
}

QString AtlasPanel::nameFor(double x, double y) const {
    const int near = view_->nearestMaterial(QPointF(x, y));
    QString name = QStringLiteral("atlas(%1,%2)").arg(x, 0, 'f', 3).arg(y, 0, 'f', 3);
    if (near >= 0) name += QStringLiteral(" ~") + view_->materialNames()[near];
    return name;
}

void AtlasPanel::openModel(const QString &path) {
    if (openWatcher_->isRunning()) return;
    if (fieldsCancel_) fieldsCancel_->store(1);  // the last model's
    setBusy(true, QStringLiteral("opening %1 (checking its store)...").arg(QFileInfo(path).fileName()));
    openWatcher_->setFuture(QtConcurrent::run([path]() -> Opened {
        Opened o;
        o.path = path;
        try {
            auto m = std::make_shared<const brdf_atlas::Model>(path.toStdString());
            if (m->latent_dim() != 2) {
                o.error = QStringLiteral("%1: the latent space is %2-D, the map needs a 2-D model")
                              .arg(path)
                              .arg(m->latent_dim());
                return o;
            }
            // Reads the map's fields saved beside the model, if any, here
            // rather than at the first map.
            try {
                o.fieldsSaved = m->saved_fields() > 0;
            } catch (const std::exception &) {
                o.fieldsSaved = false;  // unusable: built and saved anew
            }
            o.model = std::move(m);
        } catch (const std::exception &e) {
            o.error = errorText(e);
        }
        return o;
    }));
}

void AtlasPanel::validatePoint() {
    if (!view_->model() || !view_->hasMarker() || buildWatcher_->isRunning()) return;
    const QPointF m = view_->marker();
    AtlasReconstruction r;
    r.x = m.x();
    r.y = m.y();
    r.name = nameFor(r.x, r.y);
    r.modelPath = modelPath_;
    r.blend = blendRule();
    std::shared_ptr<const brdf_atlas::Model> model = view_->model();
    clock_.start();
    setBusy(true, QStringLiteral("reconstructing at (%1, %2)...").arg(r.x, 0, 'f', 4).arg(r.y, 0, 'f', 4));
    validate_->setEnabled(false);
    // The plausibility pass reads the whole store again, as long as the
    // reconstruction: it runs in the same job, off the GUI thread.
    buildWatcher_->setFuture(QtConcurrent::run([model, r]() mutable -> Built {
        Built b;
        try {
            r.dims = model->dims();
            r.table = std::make_shared<const std::vector<double>>(model->reconstruct(r.x, r.y, r.blend));
            r.plausibility = model->plausibility(r.x, r.y, r.blend);
            b.r = r;
        } catch (const std::exception &e) {
            b.error = errorText(e);
        }
        return b;
    }));
    showPlausibility();
}
