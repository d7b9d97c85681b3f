// Not compiled: fed to the layout check as engine/core/Bad.cpp.
#include "engine/render/Renderer.h"
