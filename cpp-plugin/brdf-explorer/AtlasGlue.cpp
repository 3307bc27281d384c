// AtlasGlue.cpp: see AtlasGlue.h.
#include "AtlasGlue.h"

#include <QGridLayout>
#include <QLabel>
#include <QMenu>
#include <cstdio>
#include <cstdlib>

#include "../ParameterGroupWidget.h"
#include "../ParameterWindow.h"
#include "AtlasMapWidget.h"
#include "BRDFReconstructed.h"

namespace {

AtlasPanel* panelOf( ParameterWindow* paramWnd )
{
    return paramWnd->findChild<AtlasPanel*>( "brdfAtlasPanel" );
}

}  // namespace

void brdfAtlasAttach( ParameterWindow* paramWnd, QGridLayout* layout, int row )
{
    AtlasPanel* panel = new AtlasPanel;
    panel->setVisible( false );
    panel->setMinimumHeight( 380 );
    layout->addWidget( panel, row, 0, 1, 2 );

    QObject::connect( panel, &AtlasPanel::modelOpened, panel, [panel]() { panel->setVisible( true ); } );
    // A failure is shown where the artist looks: the panel (hidden until a
    // model opens, so a model that fails to open, at start-up too, would
    // otherwise say nothing) comes up with the message in its status line.
    QObject::connect( panel, &AtlasPanel::failed, panel, [panel]( const QString& m ) {
        panel->setVisible( true );
        fprintf( stderr, "brdf-atlas: %s\n", qPrintable( m ) );
    } );
    QObject::connect( panel, &AtlasPanel::reconstructed, paramWnd,
                      [panel, paramWnd]( const AtlasReconstruction& r ) {
        QString error;
        BRDFReconstructed* b = BRDFReconstructed::create( r, &error );
        if( !b )
        {
            panel->statusLabel()->setText( error );
            fprintf( stderr, "brdf-atlas: %s\n", qPrintable( error ) );
            return;
        }
        paramWnd->addBRDF( b );
    } );

    // For scripted runs: open this model at start-up.
    const char* model = getenv( "BRDF_ATLAS_PLUGIN_MODEL" );
    if( model && *model )
        panel->openModel( QString::fromLocal8Bit( model ) );
}

void brdfAtlasAddMenuEntry( QMenu* fileMenu, ParameterWindow* paramWnd )
{
    QAction* open = fileMenu->addAction( "Open brdf-atlas model..." );
    QObject::connect( open, &QAction::triggered, paramWnd, [paramWnd]() {
        if( AtlasPanel* panel = panelOf( paramWnd ) )
            panel->chooseModel();
    } );
}

// Declared by the line apply.sh adds to ParameterWindow.h: add a BRDF made
// in memory exactly as openBRDFFile adds one it read from a file.
void ParameterWindow::addBRDF( BRDFBase* b )
{
    ParameterGroupWidget* pgw = addBRDFWidget( b );
    if( soloBRDFWidget )
        soloBRDF( pgw, soloBRDFUsesColors );
    else
        emitBRDFListChanged();
}
