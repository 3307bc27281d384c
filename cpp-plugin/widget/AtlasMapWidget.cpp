// AtlasMapWidget.cpp: AtlasMapView and the colour of a map pixel (see
// AtlasMapWidget.h); the panel around the view is in AtlasPanel.cpp.
#include "AtlasMapWidget.h"

#include <QFontMetricsF>
#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QWheelEvent>
#include <QtConcurrent/QtConcurrentRun>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>

namespace {

// A drag starts once the mouse moved this far (pixels) with the button down.
constexpr double kDragThreshold = 3.0;
// One wheel notch (120 units) zooms by 2^(1/4).
constexpr double kNotchZoom = 0.25;
// The full map starts once the window has stood still this long (ms): a
// map drawn from the model's field takes tens of milliseconds, and one
// whose window is left is cancelled, so waiting longer only adds latency.
constexpr int kSettleMs = 30;

float srgb(float v) {
    v = std::min(std::max(v, 0.0f), 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

QString errorText(const std::exception &e) { return QString::fromUtf8(e.what()); }

// How far a pixel of predictive variance v is faded towards kFadeGrey: the
// rule of `brdf-atlas map` (brdf_atlas_pictures::map_picture::fade), 0 up to
// the library's low-confidence threshold, rising linearly to kFadeMax at 1.
constexpr float kFadeGrey = 0.2f;
constexpr float kFadeMax = 0.75f;

float fade(float v) {
    const float low = float(BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE);
    return v > low ? kFadeMax * std::min(1.0f, (v - low) / (1.0f - low)) : 0.0f;
}

}  // namespace

QRgb atlasPixel(const float *rgb, float variance) {
    const float t = fade(variance);
    int c[3];
    for (int k = 0; k < 3; ++k) {
        const float v = std::min(std::max(rgb[k], 0.0f), 1.0f);
        c[k] = int(std::lround(255 * srgb(v + t * (kFadeGrey - v))));
    }
    return qRgb(c[0], c[1], c[2]);
}

// ---------------------------------------------------------------------------
// AtlasMapView

AtlasMapView::AtlasMapView(QWidget *parent)
    : QWidget(parent),
      previewWatcher_(new QFutureWatcher<MapResult>(this)),
      fullWatcher_(new QFutureWatcher<MapResult>(this)) {
    setMouseTracking(true);
    setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Expanding);
    setCursor(Qt::CrossCursor);
    debounce_.setSingleShot(true);
    debounce_.setInterval(kSettleMs);
    connect(&debounce_, &QTimer::timeout, this, &AtlasMapView::startFull);
    connect(previewWatcher_, &QFutureWatcher<MapResult>::finished, this,
            &AtlasMapView::previewFinished);
    connect(fullWatcher_, &QFutureWatcher<MapResult>::finished, this, &AtlasMapView::fullFinished);
    moved_.start();
}

AtlasMapView::~AtlasMapView() {
    // The jobs hold their own reference to the model; wait so they do not
    // outlive the watchers they report to (the full map stops early).
    if (fullCancel_) fullCancel_->store(1);
    previewWatcher_->waitForFinished();
    fullWatcher_->waitForFinished();
}

void AtlasMapView::setModel(std::shared_ptr<const brdf_atlas::Model> model) {
    model_ = std::move(model);
    names_.clear();
    points_.clear();
    hasMarker_ = false;
    hovered_ = -1;
    mapImage_ = QImage();
    contours_.clear();
    mapError_.clear();
    userMoved_ = false;
    // Maps of the previous model still on their way are never shown.
    shownGeneration_ = generation_;
    shownLevel_ = kFull + 1;
    if (model_) {
        try {
            const std::size_t n = model_->material_count();
            for (std::size_t i = 0; i < n; ++i) {
                names_ << QString::fromStdString(model_->material_name(i));
                const std::vector<double> p = model_->latent_point(i);
                points_ << QPointF(p.at(0), p.at(1));
            }
            defaultWindow_ = model_->view();
        } catch (const std::exception &e) {
            mapError_ = errorText(e);
        }
    }
    fitDefaultWindow();
    scheduleMap();
    update();
}

void AtlasMapView::redraw() {
    if (model_) scheduleMap();
}

void AtlasMapView::fitDefaultWindow() {
    const double w = std::max(1, width()), h = std::max(1, height());
    centre_ = QPointF((defaultWindow_.x0 + defaultWindow_.x1) / 2,
                      (defaultWindow_.y0 + defaultWindow_.y1) / 2);
    scale_ = std::max((defaultWindow_.x1 - defaultWindow_.x0) / w,
                      (defaultWindow_.y1 - defaultWindow_.y0) / h);
}

QPointF AtlasMapView::widgetToLatent(const QPointF &p) const {
    return QPointF(centre_.x() + (p.x() - width() / 2.0) * scale_,
                   centre_.y() - (p.y() - height() / 2.0) * scale_);
}

QPointF AtlasMapView::latentToWidget(const QPointF &x) const {
    return QPointF(width() / 2.0 + (x.x() - centre_.x()) / scale_,
                   height() / 2.0 - (x.y() - centre_.y()) / scale_);
}

BrdfAtlasView AtlasMapView::window() const {
    const double hw = width() / 2.0 * scale_, hh = height() / 2.0 * scale_;
    return BrdfAtlasView{centre_.x() - hw, centre_.x() + hw, centre_.y() - hh, centre_.y() + hh};
}

void AtlasMapView::setWindow(const QPointF &centre, double scale) {
    if (!(scale > 0) || !std::isfinite(scale) || !std::isfinite(centre.x()) ||
        !std::isfinite(centre.y())) {
        return;
    }
    centre_ = centre;
    scale_ = scale;
    userMoved_ = true;
    scheduleMap();
    update();
}

void AtlasMapView::setMarker(const QPointF &latent) {
    hasMarker_ = true;
    marker_ = latent;
    update();
    emit markerChanged(latent.x(), latent.y());
}

int AtlasMapView::nearestMaterial(const QPointF &latent) const {
    int best = -1;
    double bestD = 0;
    for (int i = 0; i < points_.size(); ++i) {
        const QPointF d = points_[i] - latent;
        const double dd = d.x() * d.x() + d.y() * d.y();
        if (best < 0 || dd < bestD) {
            best = i;
            bestD = dd;
        }
    }
    return best;
}

int AtlasMapView::materialAt(const QPointF &widgetPos) const {
    int best = -1;
    double bestD = kHitRadius * kHitRadius;
    // The nearest within the radius: in a cluster, the one under the cursor.
    for (int i = 0; i < points_.size(); ++i) {
        const QPointF d = latentToWidget(points_[i]) - widgetPos;
        const double dd = d.x() * d.x() + d.y() * d.y();
        if (dd <= bestD) {
            best = i;
            bestD = dd;
        }
    }
    return best;
}

QRectF AtlasMapView::labelRect(int i) const {
    if (i < 0 || i >= points_.size()) return QRectF();
    const QFontMetricsF fm(font());
    const QSizeF size(fm.horizontalAdvance(names_[i]) + 8, fm.height() + 4);
    const QPointF c = latentToWidget(points_[i]);
    // Up and to the right of the point; to its left or below it where that
    // would leave the widget; never wider than the widget.
    QRectF box(c + QPointF(8, -8 - size.height()), size);
    if (box.right() > width()) box.moveRight(c.x() - 8);
    if (box.top() < 0) box.moveTop(c.y() + 8);
    const double w = std::min(box.width(), double(width()));
    box.setWidth(w);
    box.moveLeft(std::min(std::max(box.left(), 0.0), width() - w));
    box.moveTop(std::min(std::max(box.top(), 0.0), std::max(0.0, height() - box.height())));
    return box;
}

bool AtlasMapView::mapPending() const {
    return model_ && (previewWatcher_->isRunning() || fullWatcher_->isRunning() ||
                      debounce_.isActive() || shownGeneration_ != generation_ ||
                      shownLevel_ != kFull);
}

void AtlasMapView::scheduleMap() {
    ++generation_;
    moved_.restart();
    // The full map of a window left behind is not worth finishing.
    if (fullCancel_ && fullGeneration_ != generation_) fullCancel_->store(1);
    startPreview();
    debounce_.start();
}

AtlasMapView::MapRequest AtlasMapView::request(int level) const {
    const double f = std::min(1.0, double(kMaxMapSide) / std::max(width(), height()));
    const int divisor = level == kFull ? 1 : kPreviewDivisor;
    MapRequest r;
    r.window = window();
    r.width = std::max(1, int(std::ceil(width() * f / divisor)));
    r.height = std::max(1, int(std::ceil(height() * f / divisor)));
    r.generation = generation_;
    r.level = level;
    return r;
}

void AtlasMapView::startPreview() {
    if (!model_ || previewWatcher_->isRunning()) {
        return;  // previewFinished starts the next one
    }
    previewWatcher_->setFuture(
        QtConcurrent::run(&AtlasMapView::computeMap, model_, request(kPreview), Cancel()));
}

void AtlasMapView::startFull() {
    if (!model_) return;
    if (fullWatcher_->isRunning()) {
        if (fullGeneration_ != generation_) fullCancel_->store(1);
        return;  // fullFinished starts the next one
    }
    fullCancel_ = std::make_shared<std::atomic<std::int32_t>>(0);
    fullGeneration_ = generation_;
    fullWatcher_->setFuture(
        QtConcurrent::run(&AtlasMapView::computeMap, model_, request(kFull), fullCancel_));
}

AtlasMapView::MapResult AtlasMapView::computeMap(std::shared_ptr<const brdf_atlas::Model> model,
                                                 MapRequest req, Cancel cancel) {
    MapResult out;
    out.window = req.window;
    out.generation = req.generation;
    out.level = req.level;
    const int width = req.width, height = req.height;
    const BrdfAtlasView win = req.window;
    try {
        // The albedo and the variance (which fades the map where the model
        // knows little) from one call: the full map's variance then comes
        // from the field its albedo does, not a product a pixel. A preview
        // takes the field the model holds for the window (so it is the full
        // map's picture, smaller), else kPreviewSamples samples a pixel.
        const brdf_atlas::Model::Map map =
            req.level == kPreview
                ? model->preview(width, height, win, kPreviewSamples)
                : model->map(width, height, win, 0, BRDF_ATLAS_BLEND_FLOOR, cancel.get());
        const std::vector<float> &rgb = map.rgb;
        const std::vector<float> &variance = map.variance;
        QImage image(width, height, QImage::Format_RGB32);
        for (int y = 0; y < height; ++y) {
            QRgb *line = reinterpret_cast<QRgb *>(image.scanLine(y));
            for (int x = 0; x < width; ++x) {
                const std::size_t p = std::size_t(y) * width + x;
                line[x] = atlasPixel(&rgb[3 * p], variance[p]);
            }
        }
        out.image = image;
        // Contours by the library, in map pixels, then into latent coordinates.
        std::vector<float> levels(kContourLevels);
        std::size_t nLevels = 0;
        brdf_atlas::check(brdf_atlas_contour_levels(rgb.data(), width, height, levels.size(),
                                                    levels.data(), levels.size(), &nLevels));
        std::size_t n = 0;
        brdf_atlas::check(brdf_atlas_contours(rgb.data(), width, height, levels.data(), nLevels,
                                              nullptr, 0, &n));
        std::vector<BrdfAtlasSegment> segs(n);
        if (n > 0) {
            brdf_atlas::check(brdf_atlas_contours(rgb.data(), width, height, levels.data(),
                                                  nLevels, segs.data(), segs.size(), &n));
        }
        const double sx = (win.x1 - win.x0) / width, sy = (win.y1 - win.y0) / height;
        out.contours.reserve(int(n));
        for (const BrdfAtlasSegment &s : segs) {
            out.contours << QLineF(win.x0 + s.x0 * sx, win.y1 - s.y0 * sy, win.x0 + s.x1 * sx,
                                   win.y1 - s.y1 * sy);
        }
    } catch (const brdf_atlas::Error &e) {
        out.cancelled = e.status() == BRDF_ATLAS_STATUS_CANCELLED;
        out.error = errorText(e);
    } catch (const std::exception &e) {
        out.error = errorText(e);
    }
    return out;
}

bool AtlasMapView::show(const MapResult &r) {
    // A result is drawn where it belongs even if the window moved
    // meanwhile, unless what is shown is newer: a later window, or the full
    // map of the same one.
    const bool newer = r.generation > shownGeneration_ ||
                       (r.generation == shownGeneration_ && r.level >= shownLevel_);
    if (r.cancelled || !newer) return false;
    if (r.error.isEmpty()) {
        mapImage_ = r.image;
        mapWindow_ = r.window;
        contours_ = r.contours;
        mapError_.clear();
    } else {
        mapError_ = r.error;
    }
    shownGeneration_ = r.generation;
    shownLevel_ = r.level;
    update();
    if (r.generation == generation_) {
        const double ms = moved_.nsecsElapsed() / 1e6;
        latencyMs_[r.level == kFull ? 1 : 0] = ms;
        // BRDF_ATLAS_PLUGIN_TIMINGS=1: each frame's latency on stderr, for
        // timing the panel in a running BRDF Explorer.
        static const bool timings = qEnvironmentVariableIsSet("BRDF_ATLAS_PLUGIN_TIMINGS");
        if (timings) {
            fprintf(stderr, "brdf-atlas panel: %dx%d %s shown %.1f ms after the last move\n",
                    r.image.width(), r.image.height(), r.level == kFull ? "map" : "preview", ms);
        }
        emit frameShown(r.level, ms);
    }
    return true;
}

void AtlasMapView::previewFinished() {
    const MapResult r = previewWatcher_->result();
    show(r);
    if (r.generation != generation_) startPreview();
}

void AtlasMapView::fullFinished() {
    const MapResult r = fullWatcher_->result();
    fullCancel_.reset();
    const bool shown = show(r);
    if (r.generation != generation_) {
        if (!debounce_.isActive()) startFull();
        return;
    }
    if (shown) emit mapReady(mapError_);
}

void AtlasMapView::paintEvent(QPaintEvent *) {
    QPainter p(this);
    p.fillRect(rect(), QColor(40, 40, 44));
    if (!model_) {
        p.setPen(QColor(200, 200, 200));
        p.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap,
                   mapError_.isEmpty() ? QStringLiteral("No brdf-atlas model open") : mapError_);
        return;
    }
    p.setRenderHint(QPainter::Antialiasing);
    p.setRenderHint(QPainter::SmoothPixmapTransform);
    if (!mapImage_.isNull()) {
        const QRectF target(latentToWidget(QPointF(mapWindow_.x0, mapWindow_.y1)),
                            latentToWidget(QPointF(mapWindow_.x1, mapWindow_.y0)));
        p.drawImage(target, mapImage_);
        // Contours: a dark line under a light one reads on any albedo.
        QVector<QLineF> lines;
        lines.reserve(contours_.size());
        for (const QLineF &l : contours_) {
            lines << QLineF(latentToWidget(l.p1()), latentToWidget(l.p2()));
        }
        p.setPen(QPen(QColor(0, 0, 0, 90), 2.0));
        p.drawLines(lines);
        p.setPen(QPen(QColor(255, 255, 255, 150), 1.0));
        p.drawLines(lines);
    }
    // The box the materials live in.
    p.setPen(QPen(QColor(255, 255, 255, 70), 1.0, Qt::DashLine));
    p.setBrush(Qt::NoBrush);
    p.drawRect(QRectF(latentToWidget(QPointF(-1, 1)), latentToWidget(QPointF(1, -1))));
    // Reference points.
    for (int i = 0; i < points_.size(); ++i) {
        const QPointF c = latentToWidget(points_[i]);
        const bool hot = i == hovered_;
        p.setPen(QPen(Qt::black, 1.0));
        p.setBrush(hot ? QColor(255, 220, 60) : QColor(255, 255, 255));
        p.drawEllipse(c, hot ? 5.0 : 3.5, hot ? 5.0 : 3.5);
        if (hot) {
            // A dark plate under the name: it reads on any albedo.
            const QRectF box = labelRect(i);
            p.setPen(Qt::NoPen);
            p.setBrush(QColor(0, 0, 0, 140));
            p.drawRoundedRect(box, 3, 3);
            p.setPen(Qt::white);
            p.drawText(box, Qt::AlignCenter, names_[i]);
        }
    }
    // Marker.
    if (hasMarker_) {
        const QPointF c = latentToWidget(marker_);
        p.setBrush(Qt::NoBrush);
        p.setPen(QPen(Qt::black, 3.0));
        p.drawEllipse(c, 7.0, 7.0);
        p.setPen(QPen(QColor(230, 40, 40), 2.0));
        p.drawEllipse(c, 7.0, 7.0);
        p.drawLine(c + QPointF(-11, 0), c + QPointF(-4, 0));
        p.drawLine(c + QPointF(4, 0), c + QPointF(11, 0));
        p.drawLine(c + QPointF(0, -11), c + QPointF(0, -4));
        p.drawLine(c + QPointF(0, 4), c + QPointF(0, 11));
    }
    if (!mapError_.isEmpty()) {
        p.setPen(QColor(255, 120, 120));
        p.drawText(rect().adjusted(6, 6, -6, -6), Qt::AlignBottom | Qt::TextWordWrap, mapError_);
    } else if (mapImage_.isNull()) {
        p.setPen(QColor(200, 200, 200));
        p.drawText(rect(), Qt::AlignCenter, QStringLiteral("computing the map..."));
    }
}

void AtlasMapView::resizeEvent(QResizeEvent *) {
    if (!userMoved_) fitDefaultWindow();
    if (model_) scheduleMap();
}

void AtlasMapView::wheelEvent(QWheelEvent *e) {
    if (!model_) return;
    const double notches = e->angleDelta().y() / 120.0;
    if (notches == 0) return;
    const QPointF at = e->position();
    const QPointF fixed = widgetToLatent(at);
    const double s = scale_ * std::pow(2.0, -kNotchZoom * notches);
    // Keep the latent point under the cursor where it is.
    const QPointF c(fixed.x() - (at.x() - width() / 2.0) * s, fixed.y() + (at.y() - height() / 2.0) * s);
    setWindow(c, s);
    e->accept();
}

void AtlasMapView::mousePressEvent(QMouseEvent *e) {
    if (e->button() != Qt::LeftButton || !model_) return;
    pressed_ = true;
    dragging_ = false;
    pressPos_ = e->localPos();
    pressCentre_ = centre_;
}

void AtlasMapView::mouseMoveEvent(QMouseEvent *e) {
    if (pressed_ && (e->buttons() & Qt::LeftButton)) {
        const QPointF d = e->localPos() - pressPos_;
        if (!dragging_ && std::hypot(d.x(), d.y()) > kDragThreshold) {
            dragging_ = true;
            setCursor(Qt::ClosedHandCursor);
        }
        if (dragging_) {
            // The latent point under the mouse follows it.
            setWindow(QPointF(pressCentre_.x() - d.x() * scale_, pressCentre_.y() + d.y() * scale_),
                      scale_);
        }
        return;
    }
    const int i = materialAt(e->localPos());
    if (i != hovered_) {
        hovered_ = i;
        update();  // the name is drawn beside the point (labelRect)
    }
}

void AtlasMapView::mouseReleaseEvent(QMouseEvent *e) {
    if (e->button() != Qt::LeftButton || !pressed_) return;
    pressed_ = false;
    if (dragging_) {
        dragging_ = false;
        setCursor(Qt::CrossCursor);
        return;
    }
    // A click on a material's point (within kHitRadius) picks that material
    // exactly; anywhere else, the point under the cursor.
    const int i = materialAt(e->localPos());
    setMarker(i >= 0 ? points_[i] : widgetToLatent(e->localPos()));
}

void AtlasMapView::leaveEvent(QEvent *) { clearHover(); }

void AtlasMapView::clearHover() {
    if (hovered_ >= 0) {
        hovered_ = -1;
        update();
    }
}
