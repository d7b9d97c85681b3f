// Not compiled: fed to the layout check as engine/physics/Bad.cpp.
#include "engine/sim/DemoScript.h"
