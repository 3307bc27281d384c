# The brdf-atlas plugin's part of BRDF Explorer's build (src/brdf/brdf.pro
# includes this file; cpp-plugin/apply.sh copied it here with the sources
# and wrote brdf-atlas-paths.pri next to it).
include(brdf-atlas-paths.pri)

QT += concurrent
INCLUDEPATH += $$PWD
HEADERS += \
    $$PWD/AtlasMapWidget.h \
    $$PWD/AtlasStatus.h \
    $$PWD/AtlasGlue.h \
    $$PWD/BRDFReconstructed.h \
    $$PWD/brdf_atlas.h \
    $$PWD/brdf_atlas.hpp
SOURCES += \
    $$PWD/AtlasMapWidget.cpp \
    $$PWD/AtlasPanel.cpp \
    $$PWD/AtlasFiles.cpp \
    $$PWD/AtlasStatus.cpp \
    $$PWD/AtlasGlue.cpp \
    $$PWD/BRDFReconstructed.cpp
CONFIG += c++17
LIBS += -L$$BRDF_ATLAS_LIBDIR -lbrdf_atlas_c -Wl,-rpath,$$BRDF_ATLAS_LIBDIR
