#pragma once
// The supervisory planner's picture on a case figure (the source's Figures 1.12-1.16): the
// obstacles' ellipses it holds, its safe curve V traced inside the curve's bounds and the
// map (nav::trace_curve), and a quiver plot of its field.
#include "sen3bot/nav/sgp.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"

namespace sen3bot::figure {

// figure.map must be set. The field is drawn with zeta's sign `direction`, an arrow of 0.4
// times the spacing every quiver_spacing_m where the field is defined (0: no quiver).
void add_sgp_layer(CaseFigure& figure, const nav::SupervisoryPlanner& sgp, int direction, double quiver_spacing_m);

}  // namespace sen3bot::figure
