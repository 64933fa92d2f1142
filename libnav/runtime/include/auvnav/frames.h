#pragma once
/** @file frames.h
 *  The frame and unit conventions of auvnav, stated once.
 *
 *  - Navigation frame `n`: local North-East-Down (NED) tangent frame, fixed to
 *    the Earth at the mission origin (latitude, longitude, height given in the
 *    mission). Positions `p_n` are metres N/E/D relative to that origin.
 *    Being Earth-fixed, the frame turns with the Earth: an inertial sensor at
 *    rest sees the Earth rate `omega_ie_n` (see earth.h).
 *  - Body frame `b`: Forward-Right-Down (Fossen, SNAME), origin at the vehicle's
 *    centre of gravity. (The paper's text and the authors' code use x forward,
 *    y left, z up; we use FRD so that body and navigation frames are both
 *    right-handed "down" frames, as in Fossen's equations.)
 *  - Sensor frames `s`: each sensor's pose in the body frame is the `sensorPose`
 *    of its observation (an mrpt::poses::CPose3D, translation in metres, yaw/
 *    pitch/roll only at the MRPT API boundary, never inside the filter).
 *  - Attitude `R_nb` (or quaternion `q_nb`) maps body vectors to navigation:
 *    v_n = R_nb * v_b.
 *  - SI units everywhere: m, s, rad, m/s, N, N·m, Pa, kg. Names carry the frame
 *    suffix (`v_n`, `omega_b`) and, where not SI-obvious, the unit (`pressure_pa`).
 */
