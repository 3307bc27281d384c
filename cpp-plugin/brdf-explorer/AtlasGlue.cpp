// AtlasGlue.cpp: see AtlasGlue.h.
#include "AtlasGlue.h"

#include <QDockWidget>
#include <QGridLayout>
#include <QLabel>
#include <QMainWindow>
#include <QMenu>
#include <QScrollArea>
#include <QSplitter>
#include <algorithm>
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

// The panel's and the BRDF list's least heights in the splitter: the map
// with its labels and buttons still usable, and two of the list's entries
// (a BRDF's entry with its parameters is about 110 px high).
const int kPanelMinHeight = 300;
const int kListMinHeight = 240;
// The parameter window's width with the panel (BRDF Explorer caps it at
// 300 px, where a BRDF's entry in the list scrolls sideways and its name is
// cut): a little more room for the names and the map.
const int kParamWindowWidth = 380;

// Put the panel and the BRDF list below it (BRDF Explorer's scroll area, the
// next row of the grid) in a vertical splitter, once: in the grid, the
// panel took the height and left the list one entry. Done when the panel
// first shows, so the window is BRDF Explorer's own until a model opens.
// If the row below is not a scroll area (upstream moved), the grid stays.
void splitPanelFromList( AtlasPanel* panel, QGridLayout* layout )
{
    if( qobject_cast<QSplitter*>( panel->parentWidget() ) )
        return;
    int index = layout->indexOf( panel );
    if( index < 0 )
        return;
    int row, column, rowSpan, columnSpan;
    layout->getItemPosition( index, &row, &column, &rowSpan, &columnSpan );
    QLayoutItem* below = layout->itemAtPosition( row + rowSpan, column );
    QScrollArea* list = below ? qobject_cast<QScrollArea*>( below->widget() ) : NULL;
    if( !list )
        return;
    layout->removeWidget( panel );
    layout->removeWidget( list );
    QSplitter* splitter = new QSplitter( Qt::Vertical );
    splitter->setObjectName( "brdfAtlasSplitter" );
    splitter->setChildrenCollapsible( false );
    splitter->addWidget( panel );
    splitter->addWidget( list );
    // Never below what its layout needs (the map's least size, the buttons
    // and the box of texts), which the splitter would otherwise cut off.
    panel->setMinimumHeight( std::max( kPanelMinHeight, panel->minimumSizeHint().height() ) );
    list->setMinimumHeight( kListMinHeight );
    // At first half each (the splitter scales these to its height); a
    // taller window then gives its height to the list, and the handle moves
    // the line between them.
    splitter->setStretchFactor( 0, 0 );
    splitter->setStretchFactor( 1, 1 );
    layout->addWidget( splitter, row, column, 1, columnSpan );
    splitter->setSizes( QList<int>() << 1 << 1 );

    // Widen the parameter window's dock to kParamWindowWidth.
    QWidget* paramWnd = layout->parentWidget();
    QDockWidget* dock = paramWnd ? qobject_cast<QDockWidget*>( paramWnd->parentWidget() ) : NULL;
    QMainWindow* main = dock ? qobject_cast<QMainWindow*>( dock->parentWidget() ) : NULL;
    if( main && paramWnd->maximumWidth() < kParamWindowWidth )
    {
        paramWnd->setMaximumWidth( kParamWindowWidth );
        main->resizeDocks( QList<QDockWidget*>() << dock, QList<int>() << kParamWindowWidth, Qt::Horizontal );
    }
}

void showPanel( AtlasPanel* panel, QGridLayout* layout )
{
    splitPanelFromList( panel, layout );
    panel->setVisible( true );
}

}  // namespace

void brdfAtlasAttach( ParameterWindow* paramWnd, QGridLayout* layout, int row )
{
    AtlasPanel* panel = new AtlasPanel;
    panel->setVisible( false );
    layout->addWidget( panel, row, 0, 1, 2 );

    QObject::connect( panel, &AtlasPanel::modelOpened, panel, [panel, layout]() { showPanel( panel, layout ); } );
    // A failure is shown where the artist looks: the panel (hidden until a
    // model opens, so a model that fails to open, at start-up too, would
    // otherwise say nothing) comes up with the message in its status line.
    QObject::connect( panel, &AtlasPanel::failed, panel, [panel, layout]( const QString& m ) {
        showPanel( panel, layout );
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
