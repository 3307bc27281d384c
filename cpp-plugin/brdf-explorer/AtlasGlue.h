// AtlasGlue.h: the brdf-atlas plugin's hooks into BRDF Explorer, called
// from the lines cpp-plugin/apply.sh inserts into ParameterWindow.cpp and
// MainWindow.cpp.
#ifndef BRDF_ATLAS_GLUE_H
#define BRDF_ATLAS_GLUE_H

class ParameterWindow;
class QGridLayout;
class QMenu;

// Put the atlas panel (hidden until a model is open) in row `row` of the
// parameter window's layout; when it first shows, it and the BRDF list
// below it go into a vertical splitter. A validated point becomes a BRDF
// in the list.
void brdfAtlasAttach( ParameterWindow* paramWnd, QGridLayout* layout, int row );

// Add "Open brdf-atlas model..." to the File menu.
void brdfAtlasAddMenuEntry( QMenu* fileMenu, ParameterWindow* paramWnd );

#endif
