#pragma once
// The shared check that an effect switched off leaves the paper's model
// bit for bit: the same inputs through a plant and an estimator built from
// the paper's parameters and from `p` give identical states at every step.
#include <gtest/gtest.h>

#include <cmath>

#include "joint_plant.h"
#include "parameters.h"
#include "torque_estimator.h"

namespace hdjoint {

// Current amplitude*sin(rate*k) A, constant load tau_ext; 400 steps of 1 ms.
// Call as ASSERT_NO_FATAL_FAILURE(expect_paper_model_bit_for_bit(...)).
inline void expect_paper_model_bit_for_bit(const Parameters& p, double amplitude, double rate, double tau_ext) {
    const Parameters paper;
    JointPlant a(paper), b(p);
    ASSERT_TRUE(a.initialize(tau_ext));
    ASSERT_TRUE(b.initialize(tau_ext));
    TorqueEstimator ea(paper), eb(p);
    for (int k = 0; k < 400; ++k) {
        const PlantInputs in{amplitude * std::sin(rate * k), tau_ext};
        ASSERT_TRUE(a.advance(1e-3, in));
        ASSERT_TRUE(b.advance(1e-3, in));
        ASSERT_EQ(a.save_state(), b.save_state()) << "plant, step " << k;
        const PlantOutputs o = a.outputs();
        ea.step({in.i_m, o.theta_m, o.theta_l});
        eb.step({in.i_m, o.theta_m, o.theta_l});
        ASSERT_EQ(ea.save_state(), eb.save_state()) << "estimator, step " << k;
    }
}

}  // namespace hdjoint
