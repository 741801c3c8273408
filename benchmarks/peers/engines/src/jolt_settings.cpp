// What JoltC 0.3.1 (joltc-sys) leaves out of its C API: PhysicsSystem::Get/SetPhysicsSettings,
// Get/SetGravity and a body's inverse mass. Compiled by build.rs against the same Jolt headers,
// with the same definitions, as joltc-sys's own build of Jolt (so the class layouts agree);
// main.rs checks on every run that the settings read back are Jolt's documented defaults.
#include <Jolt/Jolt.h>
#include <Jolt/Physics/Body/Body.h>
#include <Jolt/Physics/PhysicsSystem.h>

extern "C" {

struct PileJoltSettings {
    float baumgarte;
    float speculative_contact_distance;
    float penetration_slop;
    float linear_cast_threshold;
    float max_penetration_distance;
    unsigned num_velocity_steps;
    unsigned num_position_steps;
    float min_velocity_for_restitution;
    float time_before_sleep;
    float point_velocity_sleep_threshold;
    bool allow_sleeping;
    float gravity[3];
};

void pile_jolt_get_settings(const void *system, PileJoltSettings *out) {
    const JPH::PhysicsSystem *s = static_cast<const JPH::PhysicsSystem *>(system);
    const JPH::PhysicsSettings &p = s->GetPhysicsSettings();
    out->baumgarte = p.mBaumgarte;
    out->speculative_contact_distance = p.mSpeculativeContactDistance;
    out->penetration_slop = p.mPenetrationSlop;
    out->linear_cast_threshold = p.mLinearCastThreshold;
    out->max_penetration_distance = p.mMaxPenetrationDistance;
    out->num_velocity_steps = p.mNumVelocitySteps;
    out->num_position_steps = p.mNumPositionSteps;
    out->min_velocity_for_restitution = p.mMinVelocityForRestitution;
    out->time_before_sleep = p.mTimeBeforeSleep;
    out->point_velocity_sleep_threshold = p.mPointVelocitySleepThreshold;
    out->allow_sleeping = p.mAllowSleeping;
    JPH::Vec3 g = s->GetGravity();
    out->gravity[0] = g.GetX();
    out->gravity[1] = g.GetY();
    out->gravity[2] = g.GetZ();
}

void pile_jolt_set_settings(void *system, const PileJoltSettings *in) {
    JPH::PhysicsSystem *s = static_cast<JPH::PhysicsSystem *>(system);
    JPH::PhysicsSettings p = s->GetPhysicsSettings();
    p.mBaumgarte = in->baumgarte;
    p.mSpeculativeContactDistance = in->speculative_contact_distance;
    p.mPenetrationSlop = in->penetration_slop;
    p.mLinearCastThreshold = in->linear_cast_threshold;
    p.mMaxPenetrationDistance = in->max_penetration_distance;
    p.mNumVelocitySteps = in->num_velocity_steps;
    p.mNumPositionSteps = in->num_position_steps;
    p.mMinVelocityForRestitution = in->min_velocity_for_restitution;
    p.mTimeBeforeSleep = in->time_before_sleep;
    p.mPointVelocitySleepThreshold = in->point_velocity_sleep_threshold;
    p.mAllowSleeping = in->allow_sleeping;
    s->SetPhysicsSettings(p);
    s->SetGravity(JPH::Vec3(in->gravity[0], in->gravity[1], in->gravity[2]));
}

float pile_jolt_inverse_mass(const void *body) {
    const JPH::Body *b = static_cast<const JPH::Body *>(body);
    return b->GetMotionProperties()->GetInverseMass();
}

// the diagonal of the inverse inertia (0: that rotation is locked)
void pile_jolt_inverse_inertia(const void *body, float out[3]) {
    const JPH::Body *b = static_cast<const JPH::Body *>(body);
    JPH::Vec3 d = b->GetMotionProperties()->GetInverseInertiaDiagonal();
    out[0] = d.GetX();
    out[1] = d.GetY();
    out[2] = d.GetZ();
}

}
