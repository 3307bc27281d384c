// AtlasFiles.cpp: the panel's files: the MERL writer, the analytic export
// and the file dialogs (declared in AtlasMapWidget.h).
#include "AtlasMapWidget.h"

#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QLabel>
#include <QPushButton>
#include <QSaveFile>
#include <QSettings>
#include <QtConcurrent/QtConcurrentRun>
#include <QtEndian>

#include <algorithm>
#include <exception>

bool atlasWriteMerl(const AtlasReconstruction &r, const QString &path, QString *error) {
    auto fail = [&](const QString &why) {
        if (error) *error = QStringLiteral("%1: %2").arg(path, why);
        return false;
    };
    if (!r.table) return fail(QStringLiteral("nothing reconstructed yet"));
    const std::size_t bins = r.dims.theta_h * r.dims.theta_d * r.dims.phi_d;
    if (r.table->size() != 3 * bins) return fail(QStringLiteral("table does not match its dims"));
    QSaveFile f(path);
    if (!f.open(QIODevice::WriteOnly)) return fail(f.errorString());
    for (std::size_t d : {r.dims.theta_h, r.dims.theta_d, r.dims.phi_d}) {
        const qint32 le = qToLittleEndian(static_cast<qint32>(d));
        f.write(reinterpret_cast<const char *>(&le), sizeof le);
    }
    QByteArray chunk;
    const std::size_t step = 1 << 16;
    for (std::size_t i = 0; i < r.table->size(); i += step) {
        const std::size_t n = std::min(step, r.table->size() - i);
        chunk.resize(static_cast<int>(n * sizeof(double)));
        for (std::size_t k = 0; k < n; ++k) {
            qToLittleEndian((*r.table)[i + k], chunk.data() + k * sizeof(double));
        }
        if (f.write(chunk) != chunk.size()) return fail(f.errorString());
    }
    if (!f.commit()) return fail(f.errorString());
    return true;
}

void AtlasPanel::chooseModel() {
    const QString last =
        QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin")).value(settingsKey()).toString();
    const QString path = QFileDialog::getOpenFileName(
        this, QStringLiteral("Open brdf-atlas model"), last,
        QStringLiteral("brdf-atlas models (*.atlas *.model);;All files (*)"));
    if (!path.isEmpty()) openModel(path);
}

void AtlasPanel::saveDialog() {
    if (!last_.table) return;
    QString base = QStringLiteral("atlas_%1_%2.binary").arg(last_.x, 0, 'f', 3).arg(last_.y, 0, 'f', 3);
    const QString path = QFileDialog::getSaveFileName(this, QStringLiteral("Save as MERL .binary"), base,
                                                      QStringLiteral("MERL BRDF (*.binary)"));
    if (!path.isEmpty()) saveTo(path);
}

bool AtlasPanel::saveTo(const QString &path) {
    QString error;
    if (!atlasWriteMerl(last_, path, &error)) {
        fail(error);
        return false;
    }
    status_->setStyleSheet(QString());
    status_->setToolTip(QString());
    status_->setText(QStringLiteral("saved %1").arg(path));
    return true;
}

void AtlasPanel::exportDialog() {
    if (!view_->model() || !view_->hasMarker()) return;
    QString start = QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin")).value(exportDirKey()).toString();
    if (start.isEmpty() || !QFileInfo(start).isDir()) start = QFileInfo(modelPath_).absolutePath();
    const QString dir = QFileDialog::getExistingDirectory(
        this, QStringLiteral("Export the analytic material to directory"), start);
    if (!dir.isEmpty()) exportTo(dir);
}

void AtlasPanel::exportTo(const QString &dir) {
    std::shared_ptr<const brdf_atlas::Model> model = view_->model();
    if (!model || !view_->hasMarker() || exportWatcher_->isRunning()) return;
    QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin")).setValue(exportDirKey(), dir);
    AtlasExport e;
    e.x = view_->marker().x();
    e.y = view_->marker().y();
    e.dir = dir;
    // As `brdf-atlas export --at X,Y` names its files.
    e.stem = QStringLiteral("at_%1_%2").arg(e.x, 0, 'f', 3).arg(e.y, 0, 'f', 3);
    exportClock_.start();
    setBusy(true, QStringLiteral("fitting glTF parameters at (%1, %2)...").arg(e.x, 0, 'f', 4).arg(e.y, 0, 'f', 4));
    export_->setEnabled(false);
    exportWatcher_->setFuture(QtConcurrent::run([model, e]() mutable -> AtlasExport {
        try {
            e.parameters = model->export_analytic(e.x, e.y, e.dir.toStdString(), e.stem.toStdString());
            for (const char *ext : {"glb", "mtlx", "mitsuba.json", "fit.json"}) {
                e.files << QDir(e.dir).filePath(e.stem + QLatin1Char('.') + QLatin1String(ext));
            }
        } catch (const std::exception &ex) {
            e.error = QString::fromUtf8(ex.what());
        }
        return e;
    }));
}
