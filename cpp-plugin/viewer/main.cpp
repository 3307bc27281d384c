// atlas-viewer: the brdf-atlas map widget on its own, without BRDF Explorer.
//
//     atlas-viewer [MODEL]
//
// Opens MODEL (or, without one, the last model opened, remembered with
// QSettings), shows the map; click, Validate, Save .binary... File > Open
// brdf-atlas model... picks another one.
#include <QApplication>
#include <QLabel>
#include <QMainWindow>
#include <QMenuBar>
#include <QSettings>
#include <QStatusBar>

#include <cstdio>

#include "AtlasMapWidget.h"

int main(int argc, char **argv) {
    QApplication app(argc, argv);
    QApplication::setApplicationName(QStringLiteral("atlas-viewer"));
    const QStringList args = QApplication::arguments();
    if (args.size() > 2 || (args.size() == 2 && args[1].startsWith('-'))) {
        std::fprintf(stderr, "usage: atlas-viewer [MODEL]\n");
        return 2;
    }

    QMainWindow window;
    window.setWindowTitle(QStringLiteral("brdf-atlas viewer (library %1)")
                              .arg(QString::fromStdString(brdf_atlas::version())));
    auto *panel = new AtlasPanel;
    window.setCentralWidget(panel);
    QMenu *file = window.menuBar()->addMenu(QStringLiteral("&File"));
    file->addAction(QStringLiteral("Open brdf-atlas model..."), panel, &AtlasPanel::chooseModel,
                    QKeySequence::Open);
    file->addAction(QStringLiteral("Save .binary..."), panel, &AtlasPanel::saveDialog,
                    QKeySequence::Save);
    file->addSeparator();
    file->addAction(QStringLiteral("Quit"), &app, &QApplication::quit, QKeySequence::Quit);
    QObject::connect(panel, &AtlasPanel::reconstructed, &window, [&window](const AtlasReconstruction &r) {
        window.statusBar()->showMessage(
            QStringLiteral("%1: %2 values (%3 x %4 x %5 bins)")
                .arg(r.name)
                .arg(r.table->size())
                .arg(r.dims.theta_h)
                .arg(r.dims.theta_d)
                .arg(r.dims.phi_d));
    });
    QObject::connect(panel, &AtlasPanel::failed, &window,
                     [](const QString &m) { std::fprintf(stderr, "%s\n", qPrintable(m)); });
    window.resize(420, 560);
    window.show();

    QString model = args.size() == 2 ? args[1] : QString();
    if (model.isEmpty()) {
        model = QSettings(QStringLiteral("brdf-atlas"), QStringLiteral("plugin"))
                    .value(AtlasPanel::settingsKey())
                    .toString();
    }
    if (!model.isEmpty()) panel->openModel(model);
    return app.exec();
}
