// quad/detail/choose.h — internals of quad/: how a component's layout choices are compared
// (choose.cpp).
#pragma once
#include "quad/quad.h"

namespace genbrep::quad_detail {

// Whether cage a is to be kept rather than cage b among a component's layout choices:
// meeting the quality targets, then no collapsed quad, then (both meeting) density,
// squeezed arcs, irregular vertices off singularities, skewed quads, oversized quads,
// irregular vertices, each with its margin, then the smaller mean corner deviation
// (choose.cpp).
bool better_cage(const QuadStats& a, const QuadStats& b);
// The same with whether each meets the targets given (judged on its squared angles).
bool better_cage(const QuadStats& a, bool meets_a, const QuadStats& b, bool meets_b);
// Whether a layout's second reading (QuadOptions::off_node_price) is kept over its first:
// fewer irregular vertices off singularities, and better_cage.
bool better_second_reading(const QuadStats& second, const QuadStats& first);

}  // namespace genbrep::quad_detail
