#pragma once
#include <string>

#include <gtest/gtest.h>

#include "splat/error.h"

// Expects `statement` to throw splat::Error whose message contains every given fragment.
#define GSLAM_EXPECT_ERROR(statement, ...)                                                  \
  EXPECT_THROW(                                                                             \
      {                                                                                     \
        try {                                                                               \
          statement;                                                                        \
        } catch (const splat::Error& gslam_error) {                                         \
          for (const std::string fragment : {__VA_ARGS__}) {                                \
            EXPECT_NE(std::string(gslam_error.what()).find(fragment), std::string::npos)    \
                << "message '" << gslam_error.what() << "' lacks '" << fragment << "'";     \
          }                                                                                 \
          throw;                                                                            \
        }                                                                                   \
      },                                                                                    \
      splat::Error)
