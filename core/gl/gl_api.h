#pragma once
// The one place organsim includes GL: core-profile prototypes from GLVND's
// libOpenGL (no loader, no GLX). Include this instead of <GL/glcorearb.h>.
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>
