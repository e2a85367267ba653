// The paper's estimator (torque_estimator.h) and its UKF models
// (paper_ukf_models.h): input checks, static and constant-speed convergence,
// state save/restore.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "friction.h"
#include "paper_ukf_models.h"
#include "parameters.h"
#include "torque_estimator.h"
#include "transmission.h"

namespace hdjoint {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Encoder angles the estimator's own compliance model explains with a joint
// torque T at motor current i_m: theta_m/N - theta_l = atan law(T) +
// wg(Kt*i_m) + theta_err(theta_m, theta_l). Solved for theta_l at a given theta_m.
double consistent_theta_l(double T, double i_m, double theta_m, const Parameters& p) {
    const double spring = flexspline_torsion(T, p) + wave_generator_torsion(p.Kt * i_m, p);
    double theta_l = theta_m / p.N - spring;
    for (int it = 0; it < 60; ++it) theta_l = theta_m / p.N - spring - kinematic_error(theta_m, theta_l, p);
    return theta_l;
}

EstimatorInputs static_load(double T, double theta_m, const Parameters& p) {
    EstimatorInputs in;
    in.i_m = T / p.N / p.Kt;  // at rest: Kt*i_m = tau_f/N
    in.theta_m = theta_m;
    in.theta_l = consistent_theta_l(T, in.i_m, theta_m, p);
    return in;
}

TEST(PaperUkfModels, SystemModelIsTheExactZeroOrderHoldOfEq2) {
    Parameters p;
    const double Ts = 1e-3;
    const PaperSystemModel m(p, Ts);
    const double omega0 = 3.0, tau = 2.0, u = 0.05;
    // omega' = (u - Bm*omega - tau/N)/Jm, tau and u held: closed form.
    const double a = p.Bm / p.Jm;
    const double omega_inf = (u - tau / p.N) / p.Bm;
    const double exact = omega_inf + (omega0 - omega_inf) * std::exp(-a * Ts);
    const Vector<2> next = m.f(Vector<2>(omega0, tau), u);
    EXPECT_NEAR(next(0), exact, 1e-12 * std::fabs(exact));
    EXPECT_EQ(next(1), tau);  // random walk
    // Signs: more current speeds the motor up, more joint torque slows it down.
    EXPECT_GT(m.f(Vector<2>(0.0, 0.0), 1.0)(0), 0.0);
    EXPECT_LT(m.f(Vector<2>(0.0, 1.0), 0.0)(0), 0.0);

    // Bm = 0: pure integration omega + Ts*(u - tau/N)/Jm.
    p.Bm = 0.0;
    const PaperSystemModel m0(p, Ts);
    EXPECT_NEAR(m0.f(Vector<2>(omega0, tau), u)(0), omega0 + Ts * (u - tau / p.N) / p.Jm, 1e-12);
}

TEST(PaperUkfModels, MeasurementModelIsSpeedAndEq5Torsion) {
    Parameters p;
    const PaperMeasurementModel m(p);
    for (double tau : {-20.0, -1.0, 0.0, 0.3, 12.0}) {
        const Vector<2> z = m.h(Vector<2>(7.0, tau));
        EXPECT_EQ(z(0), 7.0);
        EXPECT_NEAR(z(1), std::atan(p.Cf * tau) / (p.Cf * p.Kf), 1e-18);
    }
}

TEST(TorqueEstimator, NaNOrInfiniteInputIsTreatedAsMissingAndNamed) {
    const Parameters p;
    struct Case {
        double EstimatorInputs::*field;
        const char* name;
    };
    for (const Case& c : {Case{&EstimatorInputs::i_m, "i_m"}, Case{&EstimatorInputs::theta_m, "theta_m"},
                          Case{&EstimatorInputs::theta_l, "theta_l"}}) {
        for (double bad : {kNaN, kInf, -kInf}) {
            TorqueEstimator est(p);
            ASSERT_EQ(est.step(static_load(1.0, 0.5, p)), EstimatorStatus::Ok);
            const EstimatorOutputs before = est.outputs();
            EstimatorInputs in = static_load(1.0, 0.5, p);
            in.*(c.field) = bad;
            std::string msg;
            EXPECT_EQ(est.step(in, &msg), EstimatorStatus::ReadingGated) << c.name;
            EXPECT_NE(msg.find(c.name), std::string::npos) << msg;
            EXPECT_NE(msg.find("not finite"), std::string::npos) << msg;
            EXPECT_NE(msg.find("treated as missing"), std::string::npos) << msg;
            EXPECT_TRUE(recoverable(EstimatorStatus::ReadingGated));
            // A sample predicted over: counted, the estimate finite, its deviation wider.
            EXPECT_EQ(est.samples(), 2);
            EXPECT_EQ(est.readings_gated(), 1);
            EXPECT_TRUE(std::isfinite(est.outputs().tau_ukf));
            EXPECT_GT(est.outputs().tau_ukf_std, before.tau_ukf_std);
            EXPECT_GT(est.outputs().tau_hat_std, before.tau_hat_std);
            // ... and a good sample afterwards is processed.
            EXPECT_TRUE(recoverable(est.step(static_load(1.0, 0.5, p))));
            EXPECT_EQ(est.samples(), 3);
            EXPECT_TRUE(std::isfinite(est.outputs().tau_ukf));
        }
    }
    // Before any reading there is nothing to predict from: nothing runs. Works without a message pointer too.
    TorqueEstimator est(p);
    EstimatorInputs in;
    in.theta_l = kNaN;
    EXPECT_EQ(est.step(in), EstimatorStatus::ReadingGated);
    EXPECT_EQ(est.samples(), 0);
    EXPECT_EQ(est.step(static_load(1.0, 0.5, p)), EstimatorStatus::Ok);
    EXPECT_EQ(est.samples(), 1);
}

std::vector<EstimatorInputs> varying_inputs(const Parameters& p, int n, int offset);

// A run of the estimator on `inputs`, with `edit(k, &in)` changing sample k's inputs.
template <class Edit>
std::vector<EstimatorOutputs> run_edited(const Parameters& p, const std::vector<EstimatorInputs>& inputs, Edit edit,
                                         std::vector<EstimatorStatus>* statuses = nullptr) {
    TorqueEstimator est(p);
    std::vector<EstimatorOutputs> out;
    for (std::size_t k = 0; k < inputs.size(); ++k) {
        EstimatorInputs in = inputs[k];
        edit(static_cast<int>(k), &in);
        const EstimatorStatus s = est.step(in);
        EXPECT_TRUE(recoverable(s)) << k;
        if (statuses) statuses->push_back(s);
        out.push_back(est.outputs());
    }
    return out;
}

TEST(TorqueEstimator, WildReadingsAreGatedAndBothFiltersRecoverWithinATenthOfASecond) {
    const Parameters p;
    const auto inputs = varying_inputs(p, 700, 0);
    const auto clean = run_edited(p, inputs, [](int, EstimatorInputs*) {});
    const double count_m = 2.0 * M_PI / p.motor_counts, count_l = 2.0 * M_PI / p.link_counts;
    struct Case {
        const char* name;
        int first, last;  // the wild samples
        double EstimatorInputs::*field;
        double value;  // set, or added when `add`
        bool add;
    };
    for (const Case& c : {Case{"i_m = 1e30", 300, 300, &EstimatorInputs::i_m, 1e30, false},
                          Case{"i_m = -1e200", 300, 300, &EstimatorInputs::i_m, -1e200, false},
                          Case{"i_m beyond 10 x i_peak", 300, 302, &EstimatorInputs::i_m, 10.1 * p.i_peak, false},
                          Case{"NaN burst on theta_m", 300, 340, &EstimatorInputs::theta_m, kNaN, false},
                          Case{"theta_m = 1e30", 300, 300, &EstimatorInputs::theta_m, 1e30, false},
                          Case{"theta_m + 1000 counts", 300, 310, &EstimatorInputs::theta_m, 1000.0 * count_m, true},
                          Case{"theta_l + 1000 counts", 300, 300, &EstimatorInputs::theta_l, 1000.0 * count_l, true},
                          Case{"theta_l - 1000 counts", 300, 320, &EstimatorInputs::theta_l, -1000.0 * count_l,
                               true}}) {
        std::vector<EstimatorStatus> statuses;
        const auto got = run_edited(p, inputs, [&](int k, EstimatorInputs* in) {
            if (k >= c.first && k <= c.last) in->*(c.field) = c.add ? in->*(c.field) + c.value : c.value;
        }, &statuses);
        for (int k = c.first; k <= c.last; ++k) {
            EXPECT_EQ(statuses[k], EstimatorStatus::ReadingGated) << c.name << " at " << k;
            EXPECT_GE(got[k].tau_ukf_std, got[c.first - 1].tau_ukf_std) << c.name << " at " << k;
        }
        for (std::size_t k = 0; k < got.size(); ++k) {
            ASSERT_TRUE(std::isfinite(got[k].tau_ukf) && std::isfinite(got[k].tau_hat)) << c.name << " at " << k;
            if (static_cast<int>(k) < c.first) {
                EXPECT_EQ(got[k].tau_ukf, clean[k].tau_ukf) << c.name;
            }
        }
        // 0.1 s after the last wild sample both filters are back on the clean run's estimate.
        const std::size_t back = static_cast<std::size_t>(c.last) + static_cast<std::size_t>(std::ceil(0.1 / p.Ts));
        for (std::size_t k = back; k < got.size(); ++k) {
            EXPECT_NEAR(got[k].tau_ukf, clean[k].tau_ukf, 0.05) << c.name << " at " << k;
            EXPECT_NEAR(got[k].omega_m, clean[k].omega_m, 0.5) << c.name << " at " << k;
            EXPECT_NEAR(got[k].tau_hat, clean[k].tau_hat, 0.05) << c.name << " at " << k;
        }
    }
}

TEST(TorqueEstimator, AReadingTheJointCanMakeIsNotGated) {
    // The encoder moving at just under omega_m_max, the current just inside its bound: every reading passes.
    Parameters p;
    const double w = 0.99 * p.omega_m_max;
    TorqueEstimator est(p);
    for (int k = 0; k < 50; ++k) {
        EstimatorInputs in;
        in.i_m = 0.99 * kWildCurrentMultiple * p.i_peak * (k % 2 ? 1.0 : -1.0);
        in.theta_m = w * k * p.Ts;
        in.theta_l = consistent_theta_l(0.0, 0.0, in.theta_m, p);
        ASSERT_NE(est.step(in), EstimatorStatus::ReadingGated) << k;
    }
    EXPECT_EQ(est.readings_gated(), 0);
}

TEST(TorqueEstimator, SingularTorsionIsReported) {
    const Parameters p;
    {
        // On the first sample: the model (or the encoders' offsets) is wrong.
        TorqueEstimator est(p);
        EstimatorInputs in = static_load(2.0, 0.0, p);
        in.theta_m += 0.5;  // 5 mrad of torsion: beyond the atan law's asymptote
        std::string msg;
        EXPECT_EQ(est.step(in, &msg), EstimatorStatus::SingularTorsion);
        EXPECT_NE(msg.find("singular torsion"), std::string::npos) << msg;
        EXPECT_NE(msg.find("check N, a0"), std::string::npos) << msg;
        EXPECT_FALSE(recoverable(EstimatorStatus::SingularTorsion));
        EXPECT_EQ(est.samples(), 0);
    }
    for (double offset : {0.5, -0.5}) {
        // Once the filters run: a glitch, predicted over, until it has lasted kMaxSingularTime.
        TorqueEstimator est(p);
        ASSERT_EQ(est.step(static_load(2.0, 0.0, p)), EstimatorStatus::Ok);
        EstimatorInputs in = static_load(2.0, 0.0, p);
        in.theta_m += offset;  // a move the joint can make in a sample, to a torsion beyond the asymptote
        const long limit = static_cast<long>(std::ceil(kMaxSingularTime / p.Ts));
        std::string msg;
        for (long k = 0; k < limit; ++k) {
            ASSERT_EQ(est.step(in, &msg), EstimatorStatus::ReadingGated) << k;
            // Said once, at the first of the run; the others are counted.
            if (k == 0) {
                EXPECT_NE(msg.find("singular torsion"), std::string::npos) << msg;
            } else {
                EXPECT_EQ(msg, "") << k;
            }
            EXPECT_TRUE(std::isfinite(est.outputs().tau_ukf));
        }
        EXPECT_EQ(est.readings_gated(), limit);
        EXPECT_EQ(est.step(in, &msg), EstimatorStatus::SingularTorsion);
        EXPECT_NE(msg.find("check N, a0"), std::string::npos) << msg;
        EXPECT_NE(msg.find("since sample 1"), std::string::npos) << msg;
        // The estimator goes on with good samples.
        EXPECT_EQ(est.step(static_load(2.0, 0.0, p)), EstimatorStatus::Ok);
        EXPECT_TRUE(std::isfinite(est.outputs().tau_ukf));
    }
    {
        // A short glitch: gated, and the next good sample is taken.
        TorqueEstimator est(p);
        ASSERT_EQ(est.step(static_load(2.0, 0.0, p)), EstimatorStatus::Ok);
        EstimatorInputs in = static_load(2.0, 0.0, p);
        in.theta_m += 0.5;
        EXPECT_EQ(est.step(in), EstimatorStatus::ReadingGated);
        EXPECT_TRUE(recoverable(est.step(static_load(2.0, 0.0, p))));
        EXPECT_EQ(est.readings_gated(), 1);
        // A huge encoder offset (1000 rad of torsion) is a jump no joint makes in a sample: gated by its size.
        in.theta_m = 1000.0 * p.N;
        std::string msg;
        EXPECT_EQ(est.step(in, &msg), EstimatorStatus::ReadingGated);
        EXPECT_NE(msg.find("theta_m moved"), std::string::npos) << msg;
    }
}

TEST(TorqueEstimator, RecoverableStatuses) {
    EXPECT_TRUE(recoverable(EstimatorStatus::Ok));
    EXPECT_TRUE(recoverable(EstimatorStatus::ReadingGated));
    EXPECT_TRUE(recoverable(EstimatorStatus::CovarianceRepaired));
    EXPECT_TRUE(recoverable(EstimatorStatus::CovarianceReset));
    EXPECT_TRUE(recoverable(EstimatorStatus::UpdateSkipped));
}

TEST(TorqueEstimator, StaticLoadConverges) {
    for (double T : {3.0, -5.0, 0.4, 0.0}) {
        Parameters p;
        p.a0 = 1e-4;
        TorqueEstimator est(p);
        const EstimatorInputs in = static_load(T, 12.3, p);
        std::vector<double> std_history;
        for (int k = 0; k < 3000; ++k) {
            ASSERT_EQ(est.step(in), EstimatorStatus::Ok) << k;
            std_history.push_back(est.outputs().tau_ukf_std);
        }
        const EstimatorOutputs& o = est.outputs();
        EXPECT_NEAR(o.tau_compliance, T, 1e-9 * (1.0 + std::fabs(T))) << T;
        EXPECT_NEAR(o.dtheta_f, flexspline_torsion(T, p), 1e-15) << T;
        EXPECT_NEAR(o.tau_ukf, T, 2e-5 * (1.0 + std::fabs(T))) << T;  // UKF bias of the atan law ~1e-5
        EXPECT_NEAR(o.omega_m, 0.0, 1e-4) << T;
        // The torque's uncertainty settles well below its initial 1 N.m.
        EXPECT_GT(o.tau_ukf_std, 0.0);
        EXPECT_LT(o.tau_ukf_std, 0.2 * p.ukf_p0_tau);
        EXPECT_NEAR(std_history.back(), std_history[2000], 1e-6);  // steady state
        EXPECT_TRUE(std::isfinite(o.nis));
    }
}

TEST(TorqueEstimator, StaticLoadConvergesFromAWrongStart) {
    // The first sample seeds the state with the compliance torque; a step in
    // load afterwards must be followed.
    Parameters p;
    TorqueEstimator est(p);
    for (int k = 0; k < 200; ++k) ASSERT_EQ(est.step(static_load(0.0, 1.0, p)), EstimatorStatus::Ok);
    EXPECT_NEAR(est.outputs().tau_ukf, 0.0, 1e-3);
    for (int k = 0; k < 3000; ++k) ASSERT_TRUE(recoverable(est.step(static_load(4.0, 1.0, p))));
    EXPECT_NEAR(est.outputs().tau_ukf, 4.0, 1e-3);
}

TEST(TorqueEstimator, ConstantSpeedWithFrictionConverges) {
    // Constant motor speed w against a joint torque T: Kt*i = Fc*tanh(w/omega_fc) + Bm*w + T/N.
    Parameters p;
    const double w = 20.0, T = 2.5;
    const double i_m = (coulomb_friction(w, p) + p.Bm * w + T / p.N) / p.Kt;
    TorqueEstimator est(p);
    for (int k = 0; k < 4000; ++k) {
        EstimatorInputs in;
        in.i_m = i_m;
        in.theta_m = 0.3 + w * k * p.Ts;
        in.theta_l = consistent_theta_l(T, i_m, in.theta_m, p);
        ASSERT_TRUE(recoverable(est.step(in))) << k;
    }
    EXPECT_NEAR(est.outputs().omega_m, w, 1e-3 * w);
    EXPECT_NEAR(est.outputs().tau_ukf, T, 2e-3 * T);
    EXPECT_NEAR(est.outputs().tau_compliance, T, 1e-8);
}

std::vector<EstimatorInputs> varying_inputs(const Parameters& p, int n, int offset) {
    std::vector<EstimatorInputs> v;
    for (int k = offset; k < offset + n; ++k) {
        const double t = k * p.Ts;
        const double T = 3.0 * std::sin(2.0 * t) + 0.5 * std::sin(37.0 * t);
        EstimatorInputs in;
        in.i_m = T / p.N / p.Kt + 0.01 * std::cos(91.0 * t);
        in.theta_m = 5.0 * std::sin(1.3 * t);
        in.theta_l = consistent_theta_l(T, in.i_m, in.theta_m, p) + 1e-6 * std::sin(713.0 * t);
        v.push_back(in);
    }
    return v;
}

void expect_same_outputs(const EstimatorOutputs& a, const EstimatorOutputs& b, int k) {
    EXPECT_EQ(a.tau_ukf, b.tau_ukf) << k;
    EXPECT_EQ(a.tau_compliance, b.tau_compliance) << k;
    EXPECT_EQ(a.omega_m, b.omega_m) << k;
    EXPECT_EQ(a.dtheta_f, b.dtheta_f) << k;
    EXPECT_EQ(a.tau_ukf_std, b.tau_ukf_std) << k;
    EXPECT_EQ(a.nis, b.nis) << k;
}

TEST(TorqueEstimator, SaveLoadStateContinuesBitIdentically) {
    const Parameters p;
    const auto first = varying_inputs(p, 300, 0);
    const auto next = varying_inputs(p, 100, 300);

    TorqueEstimator a(p);
    for (const auto& in : first) ASSERT_TRUE(recoverable(a.step(in)));
    const std::vector<double> saved = a.save_state();

    TorqueEstimator b(p);
    b.step(next[50]);  // b has a history of its own that the load must overwrite
    ASSERT_TRUE(b.load_state(saved));
    EXPECT_EQ(b.samples(), a.samples());
    expect_same_outputs(a.outputs(), b.outputs(), -1);
    EXPECT_EQ(b.save_state(), saved);

    for (std::size_t k = 0; k < next.size(); ++k) {
        const EstimatorStatus sa = a.step(next[k]);
        const EstimatorStatus sb = b.step(next[k]);
        ASSERT_EQ(sa, sb) << k;
        expect_same_outputs(a.outputs(), b.outputs(), static_cast<int>(k));
    }
    EXPECT_EQ(a.save_state(), b.save_state());
    // The continuation actually moved (not a trivially frozen filter).
    EXPECT_NE(a.save_state(), saved);
}

TEST(TorqueEstimator, SaveLoadOfAFreshEstimator) {
    // Restoring a never-stepped state must give the same first sample as a fresh one.
    const Parameters p;
    TorqueEstimator fresh(p), used(p);
    const std::vector<double> empty = fresh.save_state();
    for (const auto& in : varying_inputs(p, 20, 0)) used.step(in);
    ASSERT_TRUE(used.load_state(empty));
    const auto in = varying_inputs(p, 1, 500)[0];
    fresh.step(in);
    used.step(in);
    expect_same_outputs(fresh.outputs(), used.outputs(), 0);
}

// load_state() checks every value as the FMU does (one reading): a NaN
// anywhere, or a sample count that is negative or not whole, is refused and
// the estimator is left as it was.
TEST(TorqueEstimator, LoadStateRefusesValuesTheFmuRefuses) {
    const Parameters p;
    TorqueEstimator a(p);
    for (const auto& in : varying_inputs(p, 10, 0)) a.step(in);
    const std::vector<double> good = a.save_state();
    TorqueEstimator b(p);
    const std::vector<double> b_before = b.save_state();
    for (std::size_t k = 0; k < good.size(); ++k) {
        std::vector<double> s = good;
        s[k] = std::nan("");
        EXPECT_FALSE(b.load_state(s)) << "a NaN in value " << k << " was accepted";
    }
    EXPECT_EQ(b.save_state(), b_before);
    ASSERT_TRUE(b.load_state(good));
    EXPECT_EQ(b.save_state(), good);
}

TEST(TorqueEstimator, LoadStateRejectsMalformedData) {
    const Parameters p;
    TorqueEstimator a(p);
    for (const auto& in : varying_inputs(p, 10, 0)) a.step(in);
    std::vector<double> s = a.save_state();
    TorqueEstimator b(p);
    const std::vector<double> b_before = b.save_state();
    std::vector<double> shorter(s.begin(), s.end() - 1);
    EXPECT_FALSE(b.load_state(shorter));
    EXPECT_FALSE(b.load_state({}));
    std::vector<double> longer = s;
    longer.push_back(0.0);
    EXPECT_FALSE(b.load_state(longer));
    std::vector<double> wrong_version = s;
    wrong_version[0] += 1.0;
    EXPECT_FALSE(b.load_state(wrong_version));
    EXPECT_EQ(b.save_state(), b_before);  // untouched by rejected loads
}

}  // namespace
}  // namespace hdjoint
