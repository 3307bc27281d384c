// BRDFReconstructed.h: a BRDF Explorer measured BRDF whose table comes from
// a brdf-atlas model (a point of its latent map) instead of a MERL file.
// Part of the brdf-atlas plugin (cpp-plugin/apply.sh copies it into
// BRDF Explorer's src/brdf/brdf-atlas/).
#ifndef BRDF_RECONSTRUCTED_H
#define BRDF_RECONSTRUCTED_H

#include <QString>
#include <memory>
#include <vector>

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

    // Where the material came from (its table is not kept: see `samples`).
    const AtlasReconstruction& reconstruction() const { return recon; }

private:
    BRDFReconstructed( const AtlasReconstruction& r,
                       std::shared_ptr<const std::vector<float> > samples );
    // `r` without its table: the doubles (35 MB at 90 x 90 x 180) are the
    // panel's, for Save .binary, and are freed when it moves on.
    AtlasReconstruction recon;
    // The one copy this BRDF keeps: the table as the floats BRDF Explorer
    // draws (17.5 MB), shared with its reloads. initGL uploads brdfData (a
    // copy of it) and frees that copy, as for a MERL file.
    std::shared_ptr<const std::vector<float> > samples;
};

#endif
