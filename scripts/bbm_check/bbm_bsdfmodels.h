// The bbm models the published fits use, in the order of the header bbm's cmake
// generates from every model (alphabetical: ngan.h needs he.h before it); used in place
// of that header, since some other models need precomputed tables not in the sources.
#include "bsdfmodel/aggregatemodel.h"
#include "bsdfmodel/ashikhminshirley.h"
#include "bsdfmodel/cooktorrance.h"
#include "bsdfmodel/he.h"
#include "bsdfmodel/lafortune.h"
#include "bsdfmodel/lambertian.h"
#include "bsdfmodel/low.h"
#include "bsdfmodel/lowmicrofacet.h"
#include "bsdfmodel/lowsmooth.h"
#include "bsdfmodel/microfacet.h"
#include "bsdfmodel/ngan.h"
#include "bsdfmodel/phong.h"
#include "bsdfmodel/scaledmodel.h"
#include "bsdfmodel/ward.h"
#include "bsdfmodel/wardduer.h"
