"""Compiled Kalman-filter steps shared by the INS fine alignment and the stop filter.

Both filters have a velocity measurement z = (v_E, v_N) of states 3 and 4
(Titterton & Weston ch. 13; seed 002 eqs 4-6) and propagate with a
transition matrix Phi built by the caller.  The update uses the Joseph form.
"""

import numpy as np

from ._jit import jit


@jit
def propagate(x, p, phi_m, q_diag, dt):
    """In place: x = Phi x ; P = Phi P Phi' + diag(q) dt."""
    x[:] = phi_m @ x
    p[:, :] = phi_m @ p @ phi_m.T
    for i in range(x.shape[0]):
        p[i, i] += q_diag[i] * dt


@jit
def velocity_update(x, p, hm, eye, r_var, z_east, z_north):
    """In place, z = (z_east, z_north) measures x[3], x[4] with variance r_var:
    K = P H' (H P H' + R)^-1 ; x += K (z - H x) ; P = (I - K H) P (I - K H)' + K R K'."""
    s = hm @ p @ hm.T
    s[0, 0] += r_var
    s[1, 1] += r_var
    gain = p @ hm.T @ np.linalg.inv(s)
    innov = np.array([z_east - x[3], z_north - x[4]])
    x += gain @ innov
    ikh = eye - gain @ hm
    p[:, :] = ikh @ p @ ikh.T + r_var * (gain @ gain.T)
