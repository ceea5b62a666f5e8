// The one include for OpenGL in the viewer: GLFW's header with the GL 3.3 prototypes that Mesa's
// libGL exports (GL_GLEXT_PROTOTYPES; no loader needed, see ../shared/DEPENDENCIES.md).
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GLFW/glfw3.h>
