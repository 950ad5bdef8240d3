// OMPL 1.5.2's RRT-Connect on our grids, timed the way `host-sim bench` times our planner, so
// the two can be compared in the same run (see benches/ompl/README.md).
//
// Input: the bit-packed grid that `host-sim export` writes (cell (col, row) is bit
// row * width + col, least significant bit first; a set bit is an obstacle) and the legs file
// that `host-sim bench` writes (legs.csv: map,leg,sx,sy,gx,gy,optimal_m), all lengths in cells
// (bench converts maps of any cell size; ratios and OMPL's relative range do not change).
// Motion check: the same exact test as the core's `free_path` (cells are closed squares with a
// margin of a thousandth of a cell; the segment's rows are walked and every cell it touches is
// read). Time: thread CPU time of `solve` (the planner adds start and goal inside it), planner
// set-up excluded, as for our side where the bench's clock starts before `set_goal`.
//
// Planners: `--planner connect` (default): RRT-Connect, then OMPL's PathSimplifier
// (simplifyMax) on its first path, timed apart; `--planner informed`: Informed RRT* (path
// length objective), its first solution and its path cost after each of `--budgets` seconds
// of thread CPU time (one solve, resumed budget after budget).
//
// Output (stdout): CSV rows map,leg,seed,first_us,first_ratio,simplify_us,simplified_ratio,
// then one cost ratio per budget (empty where a value does not apply).

#include <ompl/base/MotionValidator.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

constexpr double kMargin = 1.0e-3;  // the core's CONTACT_MARGIN, in cells

struct Grid {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> bits;

    bool occupied(int col, int row) const {
        if (col < 0 || row < 0 || col >= width || row >= height) return true;
        const long i = static_cast<long>(row) * width + col;
        return (bits[static_cast<std::size_t>(i / 8)] >> (i % 8)) & 1u;
    }

    bool inside(double x, double y) const {
        return std::isfinite(x) && std::isfinite(y) && x >= 0.0 && y >= 0.0 && x <= width &&
               y <= height;
    }

    int clampIndex(double v, int max) const {
        if (!(v > 0.0)) return 0;
        return std::min(static_cast<int>(v), max);
    }

    // Whether every cell within the margin of segment (ax, ay)-(bx, by) is free.
    bool segmentFree(double ax, double ay, double bx, double by) const {
        if (!inside(ax, ay) || !inside(bx, by)) return false;
        if (ay > by) {
            std::swap(ax, bx);
            std::swap(ay, by);
        }
        const double dx = bx - ax, dy = by - ay;
        const int rowLo = clampIndex(ay - kMargin, height - 1);
        const int rowHi = clampIndex(by + kMargin, height - 1);
        const bool steep = dy > kMargin;
        const double slope = steep ? dx / dy : 0.0;
        for (int row = rowLo; row <= rowHi; ++row) {
            double x0 = ax, x1 = bx;
            if (steep) {
                const double y0 = std::max(ay, row - kMargin);
                const double y1 = std::min(by, row + 1.0 + kMargin);
                x0 = ax + (y0 - ay) * slope;
                x1 = ax + (y1 - ay) * slope;
            }
            const double lo = std::min(x0, x1) - kMargin, hi = std::max(x0, x1) + kMargin;
            if (hi < 0.0 || lo > width) continue;
            const int c1 = clampIndex(hi, width - 1);
            for (int c = clampIndex(lo, width - 1); c <= c1; ++c)
                if (occupied(c, row)) return false;
        }
        return true;
    }
};

const double *xy(const ob::State *s) {
    return s->as<ob::RealVectorStateSpace::StateType>()->values;
}

class ExactMotion : public ob::MotionValidator {
public:
    ExactMotion(const ob::SpaceInformationPtr &si, const Grid &g) : ob::MotionValidator(si), g_(g) {}

    bool checkMotion(const ob::State *s1, const ob::State *s2) const override {
        const double *a = xy(s1), *b = xy(s2);
        const bool ok = g_.segmentFree(a[0], a[1], b[0], b[1]);
        if (ok) ++valid_; else ++invalid_;
        return ok;
    }

    bool checkMotion(const ob::State *s1, const ob::State *s2,
                     std::pair<ob::State *, double> &lastValid) const override {
        // RRT-Connect does not ask for the last valid state; answer conservatively.
        const bool ok = checkMotion(s1, s2);
        if (!ok) {
            if (lastValid.first != nullptr) si_->copyState(lastValid.first, s1);
            lastValid.second = 0.0;
        }
        return ok;
    }

private:
    const Grid &g_;
};

double threadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

Grid readGrid(const std::string &path, int width, int height) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    Grid g;
    g.width = width;
    g.height = height;
    g.bits.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    const std::size_t need = (static_cast<std::size_t>(width) * height + 7) / 8;
    if (g.bits.size() < need) throw std::runtime_error(path + " is shorter than the grid");
    return g;
}

struct Leg {
    std::string map;
    int leg = 0;
    double sx = 0, sy = 0, gx = 0, gy = 0, optimal = 0;
};

std::vector<Leg> readLegs(const std::string &path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::vector<Leg> legs;
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream s(line);
        Leg l;
        if (!(s >> l.map >> l.leg >> l.sx >> l.sy >> l.gx >> l.gy >> l.optimal))
            throw std::runtime_error("bad legs line: " + line);
        legs.push_back(l);
    }
    return legs;
}

}  // namespace

// `--cold`: evicts the caches a query could reuse before it starts (64 MiB written and read
// back, outside the timed part), as `host-sim bench --cold` does for our planners.
static void flushCaches() {
    static std::vector<unsigned long long> buf((64u << 20) / 8);
    unsigned long long sum = 0;
    for (std::size_t i = 0; i < buf.size(); ++i) {
        buf[i] += i;
        sum += buf[i];
    }
    static volatile unsigned long long sink;
    sink = sum;
}

int main(int argc, char **argv) {
    if (argc < 4) {
        std::cerr << "usage: rrt_connect LEGS.csv GRID_DIR SEEDS [--planner connect|informed] "
                     "[--budgets S,S,...] [MAP=WIDTHxHEIGHT ...] [--cold]\n"
                     "  GRID_DIR holds MAP.grid from `host-sim bench`; each map's size is given "
                     "as MAP=WxH\n";
        return 2;
    }
    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
    ompl::RNG::setSeed(1);
    const auto legs = readLegs(argv[1]);
    const std::string dir = argv[2];
    const int seeds = std::stoi(argv[3]);
    std::string which = "connect";
    bool cold = false;
    std::vector<double> budgets;
    std::vector<std::pair<std::string, Grid>> grids;
    for (int i = 4; i < argc; ++i) {
        const std::string spec = argv[i];
        if (spec == "--planner" && i + 1 < argc) {
            which = argv[++i];
            continue;
        }
        if (spec == "--cold") {
            cold = true;
            continue;
        }
        if (spec == "--budgets" && i + 1 < argc) {
            std::string list = argv[++i];
            std::replace(list.begin(), list.end(), ',', ' ');
            std::istringstream in(list);
            for (double b; in >> b;) budgets.push_back(b);
            std::sort(budgets.begin(), budgets.end());
            continue;
        }
        const auto eq = spec.find('='), x = spec.find('x', eq);
        if (eq == std::string::npos || x == std::string::npos)
            throw std::runtime_error("bad map size: " + spec);
        const std::string name = spec.substr(0, eq);
        grids.emplace_back(name, readGrid(dir + "/" + name + ".grid",
                                          std::stoi(spec.substr(eq + 1, x - eq - 1)),
                                          std::stoi(spec.substr(x + 1))));
    }
    if (which != "connect" && which != "informed")
        throw std::runtime_error("unknown planner: " + which);
    std::printf("map,leg,seed,first_us,first_ratio,simplify_us,simplified_ratio");
    for (double b : budgets) std::printf(",cost_ratio_%g", b);
    std::printf("\n");
    for (const Leg &leg : legs) {
        const auto it = std::find_if(grids.begin(), grids.end(),
                                     [&](const auto &g) { return g.first == leg.map; });
        if (it == grids.end()) continue;
        const Grid &grid = it->second;
        // Seed 0 warms the process up (library pages, allocator) and is not reported: our
        // planner runs in a process that is already warm.
        for (int seed = 0; seed <= seeds; ++seed) {
            auto space = std::make_shared<ob::RealVectorStateSpace>(2);
            ob::RealVectorBounds bounds(2);
            bounds.setLow(0, 0.0);
            bounds.setHigh(0, grid.width);
            bounds.setLow(1, 0.0);
            bounds.setHigh(1, grid.height);
            space->setBounds(bounds);
            og::SimpleSetup ss(space);
            const auto si = ss.getSpaceInformation();
            ss.setStateValidityChecker([&grid](const ob::State *s) {
                const double *p = xy(s);
                return grid.inside(p[0], p[1]) &&
                       !grid.occupied(static_cast<int>(p[0]), static_cast<int>(p[1]));
            });
            si->setMotionValidator(std::make_shared<ExactMotion>(si, grid));
            ob::ScopedState<> start(space), goal(space);
            start[0] = leg.sx;
            start[1] = leg.sy;
            goal[0] = leg.gx;
            goal[1] = leg.gy;
            ss.setStartAndGoalStates(start, goal);
            const bool informed = which == "informed";
            if (informed) {
                ss.setOptimizationObjective(
                    std::make_shared<ob::PathLengthOptimizationObjective>(si));
                ss.setPlanner(std::make_shared<og::InformedRRTstar>(si));
            } else {
                ss.setPlanner(std::make_shared<og::RRTConnect>(si));
            }
            ss.setup();  // default range: 0.2 x the space's extent
            auto pdef = ss.getProblemDefinition();
            auto planner = ss.getPlanner();
            // The termination condition is made before the clock starts (harness work, as
            // our side's lists are made before its zero).
            const ob::PlannerTerminationCondition ptc =
                ob::timedPlannerTerminationCondition(10.0);
            if (cold) flushCaches();
            const double t0 = threadCpuSeconds();
            if (!informed) {
                const ob::PlannerStatus st = planner->solve(ptc);
                const double t1 = threadCpuSeconds();
                if (seed == 0) continue;
                if (st != ob::PlannerStatus::EXACT_SOLUTION) {
                    std::printf("%s,%d,%d,,,,\n", leg.map.c_str(), leg.leg, seed);
                    continue;
                }
                auto path = *pdef->getSolutionPath()->as<og::PathGeometric>();
                const double first = path.length();
                og::PathSimplifier simplifier(si);
                const double s0 = threadCpuSeconds();
                simplifier.simplifyMax(path);
                const double s1 = threadCpuSeconds();
                std::printf("%s,%d,%d,%.3f,%.4f,%.3f,%.4f\n", leg.map.c_str(), leg.leg, seed,
                            (t1 - t0) * 1e6, first / leg.optimal, (s1 - s0) * 1e6,
                            path.length() / leg.optimal);
                continue;
            }
            // Informed RRT*: one solve for the longest budget; every improved solution is
            // recorded with its CPU time (RRT* hands its path to the problem only at the end).
            std::vector<std::pair<double, double>> found;  // (CPU seconds, length)
            pdef->setIntermediateSolutionCallback(
                [&](const ob::Planner *, const std::vector<const ob::State *> &,
                    const ob::Cost c) { found.emplace_back(threadCpuSeconds() - t0, c.value()); });
            const double most = budgets.empty() ? 10.0 : budgets.back();
            planner->solve(ob::PlannerTerminationCondition([&]() {
                const double t = threadCpuSeconds() - t0;
                return t >= most || (budgets.empty() && !found.empty()) || t >= 10.0;
            }));
            double firstUs = -1.0, firstRatio = -1.0;
            if (!found.empty()) {
                firstUs = found.front().first * 1e6;
                firstRatio = found.front().second / leg.optimal;
            }
            std::vector<double> costs;
            for (double b : budgets) {
                // The best length found within the budget (none before the first solution).
                double best = -1.0;
                for (const auto &[t, len] : found)
                    if (t <= b && (best < 0.0 || len < best)) best = len;
                costs.push_back(best);
            }
            if (seed == 0) continue;
            std::printf("%s,%d,%d,", leg.map.c_str(), leg.leg, seed);
            if (firstUs >= 0.0)
                std::printf("%.3f,%.4f,,", firstUs, firstRatio);
            else
                std::printf(",,,");
            for (double c : costs) {
                if (c >= 0.0)
                    std::printf(",%.5f", c / leg.optimal);
                else
                    std::printf(",");
            }
            std::printf("\n");
        }
    }
    return 0;
}
