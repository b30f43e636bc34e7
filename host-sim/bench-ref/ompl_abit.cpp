// OMPL 1.5.2 ABIT* driver for the side-by-side benchmark of issue 6 (see host-sim/doc/abit_bench.md).
// Written for this project; it only uses OMPL's public API.
//
// Usage: ompl_abit PROBLEM_FILE FIRST_SEED NUM_SEEDS MAX_ITERATIONS MAX_SECONDS
// PROBLEM_FILE is written by `tetherbot abit-bench` (firmware::plan::geometric::GeometricProblem::write_text):
//   name NAME / dim N / lo ... / hi ... / start ... / goal ... / box lo... hi... (one line per box).
// Validity and motion checks are exact and identical to the Rust side: a state is valid inside the bounds and
// outside every (closed) box; a motion is valid when the closed segment touches no box (slab test).
// One line per seed on stdout:
//   seed solved first_time_s first_iteration final_cost iterations total_time_s edges_checked batches
// OMPL seeds its global RNG once per process (RNG::setSeed before any planner exists), so the seeds of one
// run are consecutive runs of one random stream starting at FIRST_SEED.
#include <ompl/base/MotionValidator.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/planners/informedtrees/ABITstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace ob = ompl::base;
namespace og = ompl::geometric;

struct Box
{
    std::vector<double> lo, hi;
};

struct Problem
{
    std::string name;
    unsigned dim = 0;
    std::vector<double> lo, hi, start, goal;
    std::vector<Box> boxes;
};

static std::vector<double> readRow(std::istringstream &in)
{
    std::vector<double> v;
    double x;
    while (in >> x)
        v.push_back(x);
    return v;
}

static bool loadProblem(const char *path, Problem &p)
{
    std::ifstream f(path);
    if (!f)
        return false;
    std::string line;
    while (std::getline(f, line))
    {
        std::istringstream in(line);
        std::string tag;
        in >> tag;
        if (tag == "name")
            in >> p.name;
        else if (tag == "dim")
            in >> p.dim;
        else if (tag == "lo")
            p.lo = readRow(in);
        else if (tag == "hi")
            p.hi = readRow(in);
        else if (tag == "start")
            p.start = readRow(in);
        else if (tag == "goal")
            p.goal = readRow(in);
        else if (tag == "box")
        {
            auto v = readRow(in);
            if (v.size() != 2 * p.dim)
                return false;
            p.boxes.push_back({std::vector<double>(v.begin(), v.begin() + p.dim),
                               std::vector<double>(v.begin() + p.dim, v.end())});
        }
    }
    return p.dim > 0 && p.lo.size() == p.dim && p.hi.size() == p.dim && p.start.size() == p.dim &&
           p.goal.size() == p.dim;
}

static const double *coords(const ob::State *s)
{
    return s->as<ob::RealVectorStateSpace::StateType>()->values;
}

static bool inBounds(const Problem &p, const double *x)
{
    for (unsigned i = 0; i < p.dim; ++i)
        if (x[i] < p.lo[i] || x[i] > p.hi[i])
            return false;
    return true;
}

static bool inBox(const Box &b, const double *x, unsigned dim)
{
    for (unsigned i = 0; i < dim; ++i)
        if (x[i] < b.lo[i] || x[i] > b.hi[i])
            return false;
    return true;
}

static bool segmentTouchesBox(const Box &b, const double *a, const double *c, unsigned dim)
{
    double tEnter = 0.0, tExit = 1.0;
    for (unsigned i = 0; i < dim; ++i)
    {
        double d = c[i] - a[i];
        if (d == 0.0)
        {
            if (a[i] < b.lo[i] || a[i] > b.hi[i])
                return false;
        }
        else
        {
            double t1 = (b.lo[i] - a[i]) / d, t2 = (b.hi[i] - a[i]) / d;
            double nearT = t1 < t2 ? t1 : t2, farT = t1 < t2 ? t2 : t1;
            if (nearT > tEnter)
                tEnter = nearT;
            if (farT < tExit)
                tExit = farT;
            if (tEnter > tExit)
                return false;
        }
    }
    return true;
}

class BoxValidity : public ob::StateValidityChecker
{
public:
    BoxValidity(const ob::SpaceInformationPtr &si, const Problem &p) : ob::StateValidityChecker(si), p_(p) {}
    bool isValid(const ob::State *s) const override
    {
        const double *x = coords(s);
        if (!inBounds(p_, x))
            return false;
        for (const auto &b : p_.boxes)
            if (inBox(b, x, p_.dim))
                return false;
        return true;
    }

private:
    const Problem &p_;
};

class BoxMotion : public ob::MotionValidator
{
public:
    BoxMotion(const ob::SpaceInformationPtr &si, const Problem &p) : ob::MotionValidator(si), p_(p) {}
    bool checkMotion(const ob::State *s1, const ob::State *s2) const override
    {
        const double *a = coords(s1), *c = coords(s2);
        if (!inBounds(p_, a) || !inBounds(p_, c))
        {
            ++invalid_;
            return false;
        }
        for (const auto &b : p_.boxes)
            if (segmentTouchesBox(b, a, c, p_.dim))
            {
                ++invalid_;
                return false;
            }
        ++valid_;
        return true;
    }
    bool checkMotion(const ob::State *s1, const ob::State *s2, std::pair<ob::State *, double> &lastValid) const override
    {
        bool ok = checkMotion(s1, s2);
        if (!ok)
        {
            if (lastValid.first != nullptr)
                si_->copyState(lastValid.first, s1);
            lastValid.second = 0.0;
        }
        return ok;
    }

private:
    const Problem &p_;
};

int main(int argc, char **argv)
{
    if (argc != 6)
    {
        std::fprintf(stderr, "usage: %s PROBLEM_FILE FIRST_SEED NUM_SEEDS MAX_ITERATIONS MAX_SECONDS\n", argv[0]);
        return 2;
    }
    Problem prob;
    if (!loadProblem(argv[1], prob))
    {
        std::fprintf(stderr, "cannot read problem file %s\n", argv[1]);
        return 2;
    }
    const unsigned long firstSeed = std::stoul(argv[2]);
    const unsigned numSeeds = static_cast<unsigned>(std::stoul(argv[3]));
    const unsigned maxIterations = static_cast<unsigned>(std::stoul(argv[4]));
    const double maxSeconds = std::stod(argv[5]);

    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
    ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(firstSeed == 0 ? 1 : firstSeed));

    for (unsigned s = 0; s < numSeeds; ++s)
    {
        auto space = std::make_shared<ob::RealVectorStateSpace>(prob.dim);
        ob::RealVectorBounds bounds(prob.dim);
        for (unsigned i = 0; i < prob.dim; ++i)
        {
            bounds.setLow(i, prob.lo[i]);
            bounds.setHigh(i, prob.hi[i]);
        }
        space->setBounds(bounds);
        auto si = std::make_shared<ob::SpaceInformation>(space);
        si->setStateValidityChecker(std::make_shared<BoxValidity>(si, prob));
        auto motion = std::make_shared<BoxMotion>(si, prob);
        si->setMotionValidator(motion);
        si->setup();

        ob::ScopedState<> start(space), goal(space);
        for (unsigned i = 0; i < prob.dim; ++i)
        {
            start[i] = prob.start[i];
            goal[i] = prob.goal[i];
        }
        auto pdef = std::make_shared<ob::ProblemDefinition>(si);
        pdef->setStartAndGoalStates(start, goal);
        pdef->setOptimizationObjective(std::make_shared<ob::PathLengthOptimizationObjective>(si));

        auto planner = std::make_shared<og::ABITstar>(si);
        planner->setProblemDefinition(pdef);

        using Clock = std::chrono::steady_clock;
        double firstTime = -1.0;
        long firstIteration = -1;
        Clock::time_point t0;
        pdef->setIntermediateSolutionCallback(
            [&](const ob::Planner *, const std::vector<const ob::State *> &, const ob::Cost &) {
                if (firstTime < 0.0)
                {
                    firstTime = std::chrono::duration<double>(Clock::now() - t0).count();
                    firstIteration = static_cast<long>(planner->numIterations());
                }
            });

        t0 = Clock::now();
        planner->setup();
        ob::PlannerTerminationCondition ptc([&] {
            return planner->numIterations() >= maxIterations ||
                   std::chrono::duration<double>(Clock::now() - t0).count() >= maxSeconds;
        });
        planner->solve(ptc);
        double total = std::chrono::duration<double>(Clock::now() - t0).count();
        double cost = planner->bestCost().value();
        bool solved = std::isfinite(cost);
        std::printf("%lu %d %.9f %ld %.12f %u %.9f %u %u\n", firstSeed + s, solved ? 1 : 0, firstTime,
                    firstIteration, solved ? cost : -1.0, planner->numIterations(), total,
                    motion->getValidMotionCount() + motion->getInvalidMotionCount(), planner->numBatches());
        std::fflush(stdout);
    }
    return 0;
}
