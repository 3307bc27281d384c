// AtlasMapWidget.h: the brdf-atlas map for Qt 5 Widgets.
//
// AtlasMapView draws the albedo map of a brdf-atlas model (computed by the
// C library for exactly the window shown, off the GUI thread: a small
// preview that follows every zoom and pan as it happens, then the full map
// once the motion stops, the stale one cancelled), its
// luminance contour lines, the model's materials as reference points (name
// on hover, kept inside the map) and a marker where the user clicked (on a
// material's point when the click is within a few pixels of it); the wheel
// zooms about the cursor, dragging pans. AtlasPanel puts the view beside the latent
// coordinates of the marker, a "Validate" button that reconstructs the
// material there off the GUI thread (with a busy indicator) under the blend
// rule chosen above it and says under it how physical that material is,
// a "Save .binary..." button, and "Export analytic..." that fits glTF
// parameters to the material at the marker off the GUI thread and writes
// them as glTF, MaterialX and Mitsuba 3 files into a directory
// (brdf_atlas_model_export), saying the parameters and the fit's error, and
// "Larger map", which shows the view in a window of its own. The texts
// that change sit in a scrolled box of fixed height: the map's size
// depends on the panel's alone.
// The panel emits `reconstructed` with the whole MERL table; what to do
// with it (a BRDF in BRDF Explorer's list, a file) is the host's business.
//
// Depends on Qt5Widgets, Qt5Concurrent and the brdf-atlas C library
// (brdf_atlas.h / brdf_atlas.hpp); nothing of BRDF Explorer.
#ifndef BRDF_ATLAS_MAP_WIDGET_H
#define BRDF_ATLAS_MAP_WIDGET_H

#include <QElapsedTimer>
#include <QFutureWatcher>
#include <QImage>
#include <QLineF>
#include <QMetaType>
#include <QPointF>
#include <QRectF>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <QVector>
#include <QWidget>

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "brdf_atlas.hpp"

class QComboBox;
class QLabel;
class QProgressBar;
class QPushButton;
class QScrollArea;

/// A material reconstructed at a latent point: what `AtlasPanel` hands out.
struct AtlasReconstruction {
    /// Latent point.
    double x = 0, y = 0;
    /// A display name: the coordinates and the nearest input material.
    QString name;
    /// The model file it came from.
    QString modelPath;
    /// Table dims.
    brdf_atlas::Dims dims{};
    /// The MERL table (3 * bins doubles, the data of a .binary file).
    std::shared_ptr<const std::vector<double>> table;
    /// The blend rule the table was made with: BRDF_ATLAS_BLEND_FLOOR (the
    /// library's default, the material the map draws), BRDF_ATLAS_BLEND_GP
    /// or BRDF_ATLAS_BLEND_PLAUSIBLE.
    std::int32_t blend = BRDF_ATLAS_BLEND_FLOOR;
    /// How physical the table is and what the model knows at (x, y)
    /// (brdf_atlas_model_plausibility under the same rule).
    brdf_atlas::Plausibility plausibility{};
};
Q_DECLARE_METATYPE(AtlasReconstruction)

/// An analytic material exported at a latent point: what `AtlasPanel`
/// hands out after "Export analytic...".
struct AtlasExport {
    /// Latent point.
    double x = 0, y = 0;
    /// The directory written into and the files' stem ("at_X_Y", as
    /// `brdf-atlas export --at X,Y` names them).
    QString dir, stem;
    /// The files written: STEM.glb, .mtlx, .mitsuba.json and .fit.json.
    QStringList files;
    /// The fitted parameters and table errors, as in the files.
    brdf_atlas::Analytic parameters{};
    /// The library's message where the export failed, else empty.
    QString error;
};
Q_DECLARE_METATYPE(AtlasExport)

/// Write `r` as a MERL .binary file at `path`, atomically (QSaveFile). On
/// failure returns false and sets `*error` to one line naming the file.
bool atlasWriteMerl(const AtlasReconstruction &r, const QString &path, QString *error);

/// A map pixel as the panel shows it: linear albedo `rgb` (3 floats) faded
/// towards grey where the predictive variance is above
/// BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE (the rule of `brdf-atlas map`), sRGB.
QRgb atlasPixel(const float *rgb, float variance);

/// The map canvas.
class AtlasMapView : public QWidget {
    Q_OBJECT
public:
    explicit AtlasMapView(QWidget *parent = nullptr);
    ~AtlasMapView() override;

    /// Show `model` (nullptr clears): its default window fitted to the widget.
    void setModel(std::shared_ptr<const brdf_atlas::Model> model);
    /// Draw the window shown again (preview, then full map): after the
    /// model gained what makes its maps faster.
    void redraw();
    const std::shared_ptr<const brdf_atlas::Model> &model() const { return model_; }

    /// Names and latent points of the model's materials.
    const QStringList &materialNames() const { return names_; }
    const QVector<QPointF> &materialPoints() const { return points_; }

    /// Widget <-> latent coordinates (y up in latent space).
    QPointF widgetToLatent(const QPointF &p) const;
    QPointF latentToWidget(const QPointF &x) const;

    /// Latent units per widget pixel, and the latent point at the widget's centre.
    double scale() const { return scale_; }
    QPointF centre() const { return centre_; }
    /// Set the window: latent point at the centre and latent units per pixel.
    void setWindow(const QPointF &centre, double scale);
    /// The latent window the widget shows now.
    BrdfAtlasView window() const;

    /// The marker (where the user clicked); hasMarker() false before a click.
    bool hasMarker() const { return hasMarker_; }
    QPointF marker() const { return marker_; }
    void setMarker(const QPointF &latent);

    /// Index of the material under the mouse, -1 if none.
    int hoveredMaterial() const { return hovered_; }
    /// Forget the hovered material and its name: the pointer has left
    /// (also when the view moves to another window, which sends no leave
    /// event).
    void clearHover();
    /// A material's point is under the cursor within this radius (pixels):
    /// it is hovered, and a click there picks exactly that material.
    static constexpr double kHitRadius = 7.0;
    /// Where the hovered name of material `i` is drawn: beside its point,
    /// always inside the widget (empty for no such material).
    QRectF labelRect(int i) const;
    /// Index of the material nearest to a latent point (-1 without a model).
    int nearestMaterial(const QPointF &latent) const;

    /// The last map shown: image, its window, contour segments (latent
    /// coordinates), its level (kPreview or kFull); mapPending() until the
    /// full map of the window in view is shown.
    const QImage &mapImage() const { return mapImage_; }
    int mapLevel() const { return shownLevel_; }
    BrdfAtlasView mapWindow() const { return mapWindow_; }
    const QVector<QLineF> &contours() const { return contours_; }
    bool mapPending() const;
    /// The largest side, in pixels, of a computed map (the image is scaled up
    /// beyond): a preview resolution, well within the library's limit.
    static constexpr int kMaxMapSide = 384;
    static_assert(kMaxMapSide <= BRDF_ATLAS_MAX_MAP_SIDE, "a map side the library accepts");
    /// Contour levels drawn.
    static constexpr int kContourLevels = 12;
    /// Map levels: the preview drawn while the window moves (a side
    /// kPreviewDivisor times smaller, from the field the model holds for
    /// the window, else kPreviewSamples quadrature samples a pixel), and
    /// the full map (the library's default rule) once it stops.
    static constexpr int kPreview = 0;
    static constexpr int kFull = 1;
    static constexpr int kPreviewDivisor = 6;
    static constexpr int kPreviewSamples = 64;
    /// Milliseconds from the last change of the window to the frame of
    /// `level` for it being shown (-1 before the first).
    double frameLatencyMs(int level) const { return latencyMs_[level == kFull ? 1 : 0]; }

    QSize sizeHint() const override { return QSize(280, 280); }
    QSize minimumSizeHint() const override { return QSize(160, 160); }

signals:
    /// The user clicked at latent point (x, y).
    void markerChanged(double x, double y);
    /// The full map for the current window is drawn (or failed: message non-empty).
    void mapReady(const QString &error);
    /// A frame of `level` (kPreview or kFull) for the current window is
    /// drawn, `latencyMs` after the window last changed.
    void frameShown(int level, double latencyMs);

protected:
    void paintEvent(QPaintEvent *) override;
    void resizeEvent(QResizeEvent *) override;
    void wheelEvent(QWheelEvent *) override;
    void mousePressEvent(QMouseEvent *) override;
    void mouseMoveEvent(QMouseEvent *) override;
    void mouseReleaseEvent(QMouseEvent *) override;
    void leaveEvent(QEvent *) override;

private:
    using Cancel = std::shared_ptr<std::atomic<std::int32_t>>;
    struct MapResult {
        QImage image;
        BrdfAtlasView window{};
        QVector<QLineF> contours;
        QString error;
        quint64 generation = 0;
        int level = kFull;
        bool cancelled = false;
    };
    struct MapRequest {
        BrdfAtlasView window{};
        int width = 1, height = 1;
        quint64 generation = 0;
        int level = kFull;
    };
    static MapResult computeMap(std::shared_ptr<const brdf_atlas::Model> model, MapRequest request,
                                Cancel cancel);
    MapRequest request(int level) const;
    void scheduleMap();
    void startPreview();
    void startFull();
    void previewFinished();
    void fullFinished();
    bool show(const MapResult &r);
    void fitDefaultWindow();
    int materialAt(const QPointF &widgetPos) const;

    std::shared_ptr<const brdf_atlas::Model> model_;
    QStringList names_;
    QVector<QPointF> points_;
    BrdfAtlasView defaultWindow_{-BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH, BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH,
                                 -BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH, BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH};
    QPointF centre_{0, 0};
    double scale_ = 0.01;
    bool userMoved_ = false;  // zoomed or panned: a resize keeps the window
    bool hasMarker_ = false;
    QPointF marker_;
    int hovered_ = -1;

    // Mouse: a press becomes a drag once it moves more than a few pixels.
    bool pressed_ = false;
    bool dragging_ = false;
    QPointF pressPos_;
    QPointF pressCentre_;

    QImage mapImage_;
    BrdfAtlasView mapWindow_{};
    QVector<QLineF> contours_;
    QString mapError_;
    quint64 generation_ = 0;  // of the window wanted now
    quint64 shownGeneration_ = 0;  // of the map shown, and its level
    int shownLevel_ = kPreview;
    QElapsedTimer moved_;  // since the window last changed
    double latencyMs_[2] = {-1, -1};
    QTimer debounce_;  // the full map starts once the window stops moving
    QFutureWatcher<MapResult> *previewWatcher_;
    QFutureWatcher<MapResult> *fullWatcher_;
    Cancel fullCancel_;  // of the full map being computed
    quint64 fullGeneration_ = 0;
};

/// The map with coordinates, Validate and Save.
class AtlasPanel : public QWidget {
    Q_OBJECT
public:
    explicit AtlasPanel(QWidget *parent = nullptr);
    ~AtlasPanel() override;

    AtlasMapView *mapView() const { return view_; }
    QPushButton *validateButton() const { return validate_; }
    QPushButton *saveButton() const { return save_; }
    /// "Export analytic...": enabled while a point is picked.
    QPushButton *exportButton() const { return export_; }
    /// "Larger map" (checkable): the map in a window of its own, kDetachedSide
    /// pixels square to start with and resizable, the panel's texts and
    /// buttons staying where they are; closing that window (or unchecking)
    /// brings the map back into the panel. The view is the same widget, so
    /// its window, marker and computed map go with it.
    QPushButton *detachButton() const { return detach_; }
    bool mapDetached() const;
    /// The window the map is detached into (hidden while it is attached).
    QWidget *mapWindow() const { return mapWindow_; }
    static constexpr int kDetachedSide = 640;
    /// The blend rule Validate makes the material with: "Soft floor"
    /// (BRDF_ATLAS_BLEND_FLOOR, the default), "GP" (BRDF_ATLAS_BLEND_GP) or
    /// "Stepped" (BRDF_ATLAS_BLEND_PLAUSIBLE); each item's data is its rule.
    /// Remembered across sessions.
    QComboBox *blendBox() const { return blend_; }
    /// The rule chosen in blendBox().
    std::int32_t blendRule() const;
    QProgressBar *progressBar() const { return progress_; }
    QLabel *coordinatesLabel() const { return coords_; }
    QLabel *statusLabel() const { return status_; }
    /// The box of fixed height under the buttons that holds the texts
    /// which change (coordinates, plausibility, busy bar, status), scrolled
    /// when they outgrow it, so that they never change the map's size.
    QScrollArea *textsBox() const { return details_; }
    /// Lines of text that box shows without scrolling.
    static constexpr int kTextLines = 6;
    /// The plausibility of the material validated at the marker, under the
    /// buttons; greyed while the marker is at a point not validated.
    QLabel *plausibilityLabel() const { return plausibility_; }

    /// The model file shown ("" before one is open).
    QString modelPath() const { return modelPath_; }
    /// Whether a model open, the map's fields being built, a reconstruction
    /// or an export is running.
    bool busy() const;
    /// The last reconstruction (table null before the first).
    const AtlasReconstruction &lastReconstruction() const { return last_; }
    /// The last export that succeeded (no files before the first).
    const AtlasExport &lastExport() const { return exported_; }

    /// The QSettings key of the last model opened (organisation and
    /// application names are the host's).
    static QString settingsKey() { return QStringLiteral("brdf-atlas/lastModel"); }
    /// Settings key of the blend rule chosen: "floor", "gp" or "plausible"
    /// (the CLI's --blend names); anything else is read as "floor".
    static QString blendKey() { return QStringLiteral("brdf-atlas/blend"); }
    /// Settings key of the directory exported into last.
    static QString exportDirKey() { return QStringLiteral("brdf-atlas/exportDir"); }

public slots:
    /// Open a model file off the GUI thread (checks the store); emits
    /// modelOpened or failed.
    void openModel(const QString &path);
    /// Ask for a model file (starting at the last one) and open it.
    void chooseModel();
    /// Reconstruct the material at the marker off the GUI thread; emits
    /// reconstructed or failed.
    void validatePoint();
    /// Ask for a file name and save the last reconstruction there.
    void saveDialog();
    /// Save the last reconstruction as a MERL .binary file at `path`.
    bool saveTo(const QString &path);
    /// Ask for a directory (starting at the last one) and export the
    /// analytic material at the marker into it.
    void exportDialog();
    /// Fit the analytic material at the marker (the default rule's, the
    /// soft floor's, whatever the blend chosen) off the GUI thread and write
    /// its files into the existing directory `dir`; emits exported or
    /// failed.
    void exportTo(const QString &dir);

signals:
    void modelOpened(const QString &path);
    void reconstructed(const AtlasReconstruction &r);
    void exported(const AtlasExport &e);
    void failed(const QString &message);

protected:
    /// Keeps the word-wrapped labels as tall as their texts at the panel's
    /// width, so that the layout's minimum height counts every line and a
    /// panel squeezed to its minimum (a splitter, a small window) cuts no
    /// text off.
    bool event(QEvent *e) override;
    /// The detached map's window closing brings the map back.
    bool eventFilter(QObject *watched, QEvent *e) override;

private:
    void setMapDetached(bool detached);
    void updateCoordinates();
    /// Say in the status line whether the model knows much at the marker.
    void sayConfidence();
    /// Show the last reconstruction's plausibility if it is the marker's,
    /// else a greyed line saying that Validate checks it.
    void showPlausibility();
    void setBusy(bool busy, const QString &what);
    void fail(const QString &message);
    /// Build the map's fields `brdf-atlas fit` saves (the default view's and
    /// [-3, 3]^2's) off the GUI thread and save them beside the model, for a
    /// model opened without them; the map is drawn again once they are there.
    void prepareFields(std::shared_ptr<const brdf_atlas::Model> model);
    QString nameFor(double x, double y) const;

    AtlasMapView *view_;
    QLabel *title_;
    QLabel *coords_;
    QPushButton *validate_;
    QPushButton *save_;
    QPushButton *export_;
    QPushButton *detach_;
    QWidget *mapWindow_;
    QLabel *mapAway_;
    QLabel *blendLabel_;
    QComboBox *blend_;
    QLabel *plausibility_;
    QProgressBar *progress_;
    QLabel *status_;
    QScrollArea *details_;
    QString modelPath_;
    AtlasReconstruction last_;
    AtlasExport exported_;
    QElapsedTimer clock_, exportClock_;

    struct Opened {
        std::shared_ptr<const brdf_atlas::Model> model;
        QString path;
        QString error;
        /// The model has its map's fields saved beside it (usable).
        bool fieldsSaved = true;
    };
    struct Built {
        AtlasReconstruction r;
        QString error;
    };
    QFutureWatcher<Opened> *openWatcher_;
    QFutureWatcher<Built> *buildWatcher_;
    QFutureWatcher<AtlasExport> *exportWatcher_;
    /// Building the map's fields: the error ("" on success or cancel).
    QFutureWatcher<QString> *fieldsWatcher_;
    std::shared_ptr<std::atomic<std::int32_t>> fieldsCancel_;
};

#endif  // BRDF_ATLAS_MAP_WIDGET_H
