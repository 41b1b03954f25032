// edgeplane: the evaluation metrics of EVALUATION.md (D2MC, thesis SSIM, SegComp, plane
// precision / recall).  Host only, no I/O.
#pragma once
#include "edgeplane/metrics/d2mc.hpp"
#include "edgeplane/metrics/evaluation.hpp"
#include "edgeplane/metrics/hungarian.hpp"
#include "edgeplane/metrics/overlap_table.hpp"
#include "edgeplane/metrics/plane_equation.hpp"
#include "edgeplane/metrics/plane_match.hpp"
#include "edgeplane/metrics/scored_mask.hpp"
#include "edgeplane/metrics/segcomp.hpp"
#include "edgeplane/metrics/ssim.hpp"
