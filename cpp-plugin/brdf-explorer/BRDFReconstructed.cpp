// BRDFReconstructed.cpp: see BRDFReconstructed.h.
#include "BRDFReconstructed.h"

#include <algorithm>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

BRDFReconstructed* BRDFReconstructed::create( const AtlasReconstruction& r, QString* error )
{
    // BRDF Explorer's measured shader indexes the MERL layout at 90 x 90 x 180.
    if( !r.table || r.dims.theta_h != 90 || r.dims.theta_d != 90 || r.dims.phi_d != 180 ||
        r.table->size() != 3 * std::size_t(90 * 90 * 180) )
    {
        if( error )
            *error = QString( "%1: the model's tables are %2 x %3 x %4 bins; BRDF Explorer "
                              "shows 90 x 90 x 180 MERL tables only" )
                         .arg( r.modelPath ).arg( r.dims.theta_h ).arg( r.dims.theta_d ).arg( r.dims.phi_d );
        return NULL;
    }
    BRDFReconstructed* b = new BRDFReconstructed( r );
    // What BRDFMeasuredMERL::loadMERLData does with a file's data: the
    // sample count and the floats that initGL uploads (and frees).
    b->numBRDFSamples = int( r.table->size() / 3 );
    b->brdfData = new float[ r.table->size() ];
    std::copy( r.table->begin(), r.table->end(), b->brdfData );
    return b;
}

BRDFReconstructed::BRDFReconstructed( const AtlasReconstruction& r )
    : recon( r )
{
    recon.table.reset();
    name = r.name.toStdString();
    tbo = 0;
    tex = 0;
}

BRDFReconstructed::~BRDFReconstructed()
{
    // Never drawn: the floats were not uploaded (BRDFMeasuredMERL keeps them).
    delete[] brdfData;
    brdfData = NULL;
}

void BRDFReconstructed::initGL()
{
    const bool upload = !initializedGL;
    BRDFMeasuredMERL::initGL();
#if defined(__GLIBC__)
    if( upload )
        malloc_trim( 0 );
#endif
}

BRDFBase* BRDFReconstructed::cloneBRDF( bool resetToDefaults )
{
    BRDFReconstructed* b = new BRDFReconstructed( recon );
    b->numBRDFSamples = numBRDFSamples;
    // Hand the table over: the OpenGL buffer once uploaded (the contexts of
    // BRDF Explorer's views share it), the floats before. This BRDF keeps
    // none; ~BRDFMeasuredMERL then deletes buffer 0, which OpenGL ignores.
    b->brdfData = brdfData;
    brdfData = NULL;
    b->tbo = tbo;
    b->tex = tex;
    b->initializedGL = initializedGL;
    tbo = 0;
    tex = 0;
    if( !resetToDefaults )
        syncParametersIntoBRDF( b );
    return b;
}
