// BRDFReconstructed.h: a BRDF Explorer measured BRDF whose table comes from
// a brdf-atlas model (a point of its latent map) instead of a MERL file.
// Part of the brdf-atlas plugin (cpp-plugin/apply.sh copies it into
// BRDF Explorer's src/brdf/brdf-atlas/).
#ifndef BRDF_RECONSTRUCTED_H
#define BRDF_RECONSTRUCTED_H

#include <QString>

#include "../BRDFMeasuredMERL.h"
#include "AtlasMapWidget.h"

class BRDFReconstructed : public BRDFMeasuredMERL
{
public:
    // A new BRDF holding the table of `r`, named r.name; NULL (and *error
    // set) if the table is not the 90 x 90 x 180 bins BRDF Explorer draws.
    static BRDFReconstructed* create( const AtlasReconstruction& r, QString* error );

    // "Reload BRDF": a fresh BRDF from the same reconstruction (the same
    // bits as the first time), keeping the parameters unless asked not to.
    virtual BRDFBase* cloneBRDF( bool resetToDefaults );

    const AtlasReconstruction& reconstruction() const { return recon; }

private:
    explicit BRDFReconstructed( const AtlasReconstruction& r );
    AtlasReconstruction recon;
};

#endif
