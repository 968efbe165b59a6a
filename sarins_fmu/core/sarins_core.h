/* sarins_core: the C physics core of sarins-fmu.
 *
 * Plain C11, no libm: the math functions are the core's own (smath.h).  No globals, no heap allocation inside the step
 * functions, reentrant: every function works on the arrays or the state
 * struct it is given.  Units are SI (rad, rad/s, m, m/s, s; temperatures in
 * degC where stated); frames follow the Python library: navigation frame
 * ENU, body frame right-front-up, mat_nb projects body onto navigation
 * axes, quaternions are [w x y z].
 *
 * Component headers are included from here; the Python binding is
 * sarins_fmu/core/_lib.py (ctypes).
 */
#ifndef SARINS_CORE_H
#define SARINS_CORE_H

#include <stdint.h>

#include "smath.h"

/* ABI version of the library; the binding refuses a library of another one. */
#define SARINS_CORE_ABI 8

int sarins_core_abi(void);

/* IMU family (issue 18) */
#include "rng.h"
#include "thermal.h"
#include "correlated.h"
#include "imu.h"
#include "imu_params.h"
#include "imu_build.h"

/* INS family and turntable (issue 18) */
#include "earth.h"
#include "rotations.h"
#include "filter.h"
#include "ins.h"
#include "turntable.h"
#include "schedule.h"
#include "ambient.h"
#include "traj.h"
#include "aided_imu.h"
#include "nav3.h"
#include "gnss.h"
#include "eskf.h"
#include "odo.h"
#include "aid_noise.h"
#include "zvd.h"
#include "vibration.h"
#include "ins_fmu_step.h"

/* trained networks: model files, inference kernels, identifier and compensators */
#include "netfile.h"
#include "nets.h"
#include "netmodel.h"

/* seed 002's online model update: the stop filter, the forgetting-factor RLS, Fig. 2's logic */
#include "matrix.h"
#include "stop_filter.h"
#include "rls.h"
#include "online.h"

/* text IMU logs: sample lines parsed into doubles (sarins_fmu.imu_log) */
#include "log_parse.h"

/* seed 002's land vehicle: trajectory, body sway and vibration */
#include "vehicle.h"

#endif
