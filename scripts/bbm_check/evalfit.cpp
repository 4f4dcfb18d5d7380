// Evaluate every fit of a bbm .fit file with bbm itself: bbm::io::importFIT reads the
// file (bbm's own parser and model definitions), each BSDF's eval(in, out) is printed.
// Pairs of unit directions come on stdin, one "ix iy iz ox oy oz" per line; the output is
// one "name index r g b" line per fit and pair.  Built by run.sh against a bbm checkout
// (native backbone, doubleRGB); written for plausible's cross-check, see README.md.
#include <iomanip>
#include <iostream>
#include <map>
#include <vector>

#include "bbm.h"
#include "io/fit.h"

using namespace bbm;
BBM_IMPORT_CONFIG( doubleRGB );

int main(int argc, char** argv)
{
  if(argc != 2) { std::cerr << "usage: evalfit FILE.fit < pairs" << std::endl; return 2; }
  std::map<std::string, bsdf_ptr<Config>> data;
  io::importFIT<Config>(argv[1], data);
  std::vector<Vec3d> in, out;
  double a, b, c, d, e, f;
  while(std::cin >> a >> b >> c >> d >> e >> f) { in.push_back(Vec3d(a, b, c)); out.push_back(Vec3d(d, e, f)); }
  std::cout << std::setprecision(17);
  for(auto& [name, bsdf] : data)
    for(size_t i = 0; i < in.size(); ++i)
    {
      Spectrum s = bsdf->eval(in[i], out[i]);
      std::cout << name << " " << i << " " << s[0] << " " << s[1] << " " << s[2] << "\n";
    }
  return 0;
}
