// BRDFReconstructed.cpp: see BRDFReconstructed.h.
#include "BRDFReconstructed.h"

#include <algorithm>

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
    auto floats = std::make_shared<std::vector<float> >( r.table->begin(), r.table->end() );
    return new BRDFReconstructed( r, std::move( floats ) );
}

BRDFReconstructed::BRDFReconstructed( const AtlasReconstruction& r,
                                      std::shared_ptr<const std::vector<float> > s )
    : recon( r ), samples( std::move( s ) )
{
    recon.table.reset();
    // What BRDFMeasuredMERL::loadMERLData does with a file's data: the name,
    // the sample count and the float copy that initGL uploads (and frees).
    name = r.name.toStdString();
    numBRDFSamples = int( samples->size() / 3 );
    brdfData = new float[ samples->size() ];
    std::copy( samples->begin(), samples->end(), brdfData );
}

BRDFBase* BRDFReconstructed::cloneBRDF( bool resetToDefaults )
{
    BRDFReconstructed* b = new BRDFReconstructed( recon, samples );
    if( !resetToDefaults )
        syncParametersIntoBRDF( b );
    return b;
}
