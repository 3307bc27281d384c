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
    virtual ~BRDFReconstructed();

    // "Reload BRDF" (BRDF Explorer's only caller, which then deletes this
    // BRDF): a fresh BRDF that takes over this one's table, the same bits,
    // keeping the parameters unless asked not to.
    virtual BRDFBase* cloneBRDF( bool resetToDefaults );

    // Where the material came from (its table is not kept here).
    const AtlasReconstruction& reconstruction() const { return recon; }

protected:
    // BRDFMeasuredMERL's upload, then the freed floats (and the doubles of
    // earlier reconstructions) handed back to the system: glibc keeps
    // freed blocks of this size in the heap, which grew by some 10 MB per
    // validated material in a running BRDF Explorer without it.
    virtual void initGL();

private:
    explicit BRDFReconstructed( const AtlasReconstruction& r );
    // `r` without its table: the doubles (35 MB at 90 x 90 x 180) are the
    // panel's, for Save .binary, and are freed when it moves on.
    AtlasReconstruction recon;
    // The table itself is one copy, BRDF Explorer's: the floats of brdfData
    // (17.5 MB) until the first frame, then the OpenGL buffer initGL
    // uploads them to (and frees them), as for a MERL file. A reload hands
    // the buffer (or brdfData) over to the new BRDF instead of copying it.
};

#endif
