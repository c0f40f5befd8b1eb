// The registration of the shipped disturbance's twin (disturbance.hpp), in a file of its own so
// that a twin compiled apart, which includes the header, registers only its own.
#include "disturbance.hpp"

namespace nnrobust {
NNROBUST_DISTURBANCE("sinusoid", SinusoidalDisturbance);  // the twin of every shipped kind
}  // namespace nnrobust
