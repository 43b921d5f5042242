// Precompiled header of the test executables (cmake/BuildSpeed.cmake): the libraries' one plus
// GoogleTest.
#pragma once
#include "common.h"

#include <filesystem>
#include <gtest/gtest.h>
