// The parameter table (parameter_table.def): complete, unique, defaults in
// range, and validate()/find_parameter() behave as documented.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "parameters.h"

namespace hdjoint {
namespace {

// The names CONTRACT.md fixes as the public interface, with the FMU(s) that carry them.
struct Expected {
    const char* name;
    bool estimator;
    bool plant;
};
const Expected kContractNames[] = {
    {"N", true, true},        {"Kt", true, true},       {"Jm", true, true},       {"Bm", true, true},
    {"Fc", true, true},       {"Kf", true, true},       {"Cf", true, true},       {"Kw", true, true},
    {"Cw", true, true},       {"a0", true, true},       {"al1", true, true},      {"bl1", true, true},
    {"omega_l", true, true},  {"aw1", true, true},      {"bw1", true, true},      {"aw2", true, true},
    {"bw2", true, true},      {"omega_w", true, true},  {"Jl", true, true},       {"Bl", true, true},
    {"mgl", true, true},      {"motor_counts", true, true}, {"link_counts", true, true},
    {"ukf_alpha", true, false}, {"ukf_beta", true, false}, {"ukf_kappa", true, false},
};

// The number after "= " in a validate() message.
double value_in_message(const std::string& msg) {
    const auto at = msg.find("= ");
    if (at == std::string::npos) return -12345.678;
    return std::strtod(msg.c_str() + at + 2, nullptr);
}

TEST(Parameters, TableHasEveryContractNameInTheRightScope) {
    for (const Expected& e : kContractNames) {
        const auto i = find_parameter(e.name);
        ASSERT_TRUE(i.has_value()) << e.name << " missing from parameter_table.def";
        const ParameterInfo& info = parameter_table()[*i];
        EXPECT_STREQ(info.name, e.name);
        EXPECT_EQ(in_estimator(info.scope), e.estimator) << e.name;
        EXPECT_EQ(in_plant(info.scope), e.plant) << e.name;
    }
}

TEST(Parameters, NamesAndMembersAreUnique) {
    std::set<std::string> names;
    const ParameterInfo* t = parameter_table();
    ASSERT_GT(parameter_count(), 30u);
    for (std::size_t i = 0; i < parameter_count(); ++i) {
        EXPECT_TRUE(names.insert(t[i].name).second) << "duplicate parameter " << t[i].name;
        for (std::size_t j = 0; j < i; ++j)
            EXPECT_NE(t[i].member, t[j].member) << t[i].name << " and " << t[j].name << " share a field";
    }
    EXPECT_EQ(names.size(), parameter_count());
}

TEST(Parameters, EveryEntryIsDocumented) {
    const ParameterInfo* t = parameter_table();
    for (std::size_t i = 0; i < parameter_count(); ++i) {
        EXPECT_GT(std::string(t[i].unit).size(), 0u) << t[i].name;
        EXPECT_GT(std::string(t[i].description).size(), 10u) << t[i].name;
        EXPECT_LE(t[i].min, t[i].max) << t[i].name;
    }
}

TEST(Parameters, DefaultsAreInsideTheirRangesAndMatchTheStruct) {
    const Parameters p;
    const ParameterInfo* t = parameter_table();
    for (std::size_t i = 0; i < parameter_count(); ++i) {
        EXPECT_TRUE(std::isfinite(t[i].default_value)) << t[i].name;
        EXPECT_GE(t[i].default_value, t[i].min) << t[i].name;
        EXPECT_LE(t[i].default_value, t[i].max) << t[i].name;
        EXPECT_EQ(p.*(t[i].member), t[i].default_value) << t[i].name;
    }
    EXPECT_FALSE(validate(p, true, true).has_value()) << *validate(p, true, true);
    EXPECT_FALSE(validate(p, true, false).has_value());
    EXPECT_FALSE(validate(p, false, true).has_value());
}

TEST(Parameters, MemberPointerAddressesTheNamedField) {
    // Writing through the table's member pointer changes exactly that field.
    Parameters p;
    p.*(parameter_table()[*find_parameter("Kf")].member) = 1234.5;
    EXPECT_EQ(p.Kf, 1234.5);
    p.*(parameter_table()[*find_parameter("ukf_r_torsion")].member) = 7e-7;
    EXPECT_EQ(p.ukf_r_torsion, 7e-7);
    p.*(parameter_table()[*find_parameter("mgl")].member) = -3.0;
    EXPECT_EQ(p.mgl, -3.0);
}

TEST(Parameters, FindParameter) {
    const auto n = find_parameter("N");
    ASSERT_TRUE(n.has_value());
    EXPECT_STREQ(parameter_table()[*n].name, "N");
    const auto last = parameter_count() - 1;
    EXPECT_EQ(find_parameter(parameter_table()[last].name), std::optional<std::size_t>(last));
    for (std::size_t i = 0; i < parameter_count(); ++i)
        EXPECT_EQ(find_parameter(parameter_table()[i].name), std::optional<std::size_t>(i));
    EXPECT_FALSE(find_parameter("").has_value());
    EXPECT_FALSE(find_parameter("n").has_value());  // case-sensitive
    EXPECT_FALSE(find_parameter("Kf ").has_value());
    EXPECT_FALSE(find_parameter("not_a_parameter").has_value());
}

TEST(Parameters, ValidateRejectsNonPositiveGearRatio) {
    for (double bad : {0.0, -1.0, -100.0}) {
        Parameters p;
        p.N = bad;
        const auto msg = validate(p, true, true);
        ASSERT_TRUE(msg.has_value()) << "N = " << bad << " accepted";
        EXPECT_NE(msg->find("parameter N "), std::string::npos) << *msg;
        EXPECT_EQ(value_in_message(*msg), bad) << *msg;
        // Both FMUs carry N.
        EXPECT_TRUE(validate(p, true, false).has_value());
        EXPECT_TRUE(validate(p, false, true).has_value());
    }
}

TEST(Parameters, ValidateRejectsNaNAndInfinity) {
    Parameters p;
    p.Kt = std::numeric_limits<double>::quiet_NaN();
    auto msg = validate(p, true, false);
    ASSERT_TRUE(msg.has_value());
    EXPECT_NE(msg->find("parameter Kt "), std::string::npos) << *msg;
    EXPECT_TRUE(std::isnan(value_in_message(*msg))) << *msg;

    Parameters q;
    q.Jl = std::numeric_limits<double>::infinity();
    msg = validate(q, false, true);
    ASSERT_TRUE(msg.has_value());
    EXPECT_NE(msg->find("parameter Jl "), std::string::npos) << *msg;
    EXPECT_TRUE(std::isinf(value_in_message(*msg))) << *msg;
}

TEST(Parameters, ValidateRejectsOutOfRangeAndAcceptsBounds) {
    const ParameterInfo& kf = parameter_table()[*find_parameter("Kf")];
    Parameters p;
    p.Kf = kf.max * 10.0;
    auto msg = validate(p, true, true);
    ASSERT_TRUE(msg.has_value());
    EXPECT_NE(msg->find("parameter Kf "), std::string::npos) << *msg;
    EXPECT_EQ(value_in_message(*msg), p.Kf) << *msg;

    p.Kf = kf.max;  // the range is inclusive
    EXPECT_FALSE(validate(p, true, true).has_value());
    p.Kf = kf.min;
    EXPECT_FALSE(validate(p, true, true).has_value());
    p.Kf = std::nextafter(kf.min, 0.0);
    EXPECT_TRUE(validate(p, true, true).has_value());

    Parameters q;
    q.al1 = 0.02;  // a kinematic error amplitude beyond +-0.01 rad
    msg = validate(q, true, true);
    ASSERT_TRUE(msg.has_value());
    EXPECT_NE(msg->find("parameter al1 "), std::string::npos) << *msg;
    EXPECT_EQ(value_in_message(*msg), 0.02) << *msg;
}

TEST(Parameters, EncoderCountsTooFewToQuantiseAreRefused) {
    // Issue 12: motor_counts = 5e-324 was in range and 2*pi/counts overflowed to inf.
    for (const char* name : {"motor_counts", "link_counts"}) {
        for (double counts : {5e-324, 1e-300, 0.5}) {
            Parameters p;
            p.*(parameter_table()[*find_parameter(name)].member) = counts;
            for (auto [estimator, plant] : {std::pair{true, false}, std::pair{false, true}}) {
                const auto msg = validate(p, estimator, plant);
                ASSERT_TRUE(msg.has_value()) << name << " = " << counts;
                EXPECT_NE(msg->find(name), std::string::npos) << *msg;
                EXPECT_NE(msg->find("use 0 to disable"), std::string::npos) << *msg;
            }
        }
        Parameters p;
        p.*(parameter_table()[*find_parameter(name)].member) = 0.0;  // off
        EXPECT_FALSE(validate(p, true, true).has_value());
        p.*(parameter_table()[*find_parameter(name)].member) = 1.0;  // the fewest that quantise
        EXPECT_FALSE(validate(p, true, true).has_value());
    }
}

TEST(Parameters, ValidateChecksOnlyTheParametersTheFmuCarries) {
    Parameters p;
    p.Fl = -1.0;  // plant only
    EXPECT_FALSE(validate(p, true, false).has_value());
    ASSERT_TRUE(validate(p, false, true).has_value());
    EXPECT_NE(validate(p, false, true)->find("Fl"), std::string::npos);

    Parameters q;
    q.ukf_alpha = 0.0;  // estimator only
    EXPECT_FALSE(validate(q, false, true).has_value());
    ASSERT_TRUE(validate(q, true, false).has_value());
    EXPECT_NE(validate(q, true, false)->find("ukf_alpha"), std::string::npos);

    // Every parameter, set invalid on its own, is caught by the FMU(s) that carry it.
    for (std::size_t i = 0; i < parameter_count(); ++i) {
        const ParameterInfo& info = parameter_table()[i];
        Parameters r;
        r.*(info.member) = std::numeric_limits<double>::quiet_NaN();
        const auto est = validate(r, true, false);
        const auto plant = validate(r, false, true);
        EXPECT_EQ(est.has_value(), in_estimator(info.scope)) << info.name;
        EXPECT_EQ(plant.has_value(), in_plant(info.scope)) << info.name;
        const auto both = validate(r, true, true);
        ASSERT_TRUE(both.has_value()) << info.name;
        EXPECT_NE(both->find(std::string("parameter ") + info.name + " "), std::string::npos) << *both;
    }
}

// parameter_tolerance.def joins the table by name: a misspelt or removed
// parameter must not leave a prior that nothing reads.
TEST(Parameters, EveryToleranceNamesAParameterOnceWithACitedSpread) {
    std::set<std::string> seen;
    ASSERT_GT(tolerance_count(), 10u);
    for (std::size_t i = 0; i < tolerance_count(); ++i) {
        const ToleranceInfo& t = tolerance_table()[i];
        EXPECT_TRUE(find_parameter(t.name).has_value()) << t.name << " in parameter_tolerance.def is not a parameter";
        EXPECT_TRUE(seen.insert(t.name).second) << "two tolerances for " << t.name;
        EXPECT_GE(t.relative, 0.0) << t.name;
        EXPECT_GE(t.absolute, 0.0) << t.name;
        EXPECT_GT(t.relative + t.absolute, 0.0) << t.name << " has a zero-width prior";
        EXPECT_GT(std::string(t.source).size(), 4u) << t.name << " cites no source";
        EXPECT_EQ(find_tolerance(t.name), &t);
    }
    EXPECT_EQ(find_tolerance("N"), nullptr);  // the gear ratio is exact: never calibrated
}

}  // namespace
}  // namespace hdjoint
