"""The robot's geometry from a trajectory row (docs/model.md §1): platform
pose, wheel frames with steer and camber, torus surfaces, contact forces in
world coordinates. Used by Fig. 5 and the 3D replay."""

import math

import numpy as np

JOINTS = ("phi1", "alpha1", "delta2", "alpha2", "delta3", "alpha3")


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


# M0 = Rx(-π/2) turns the wheel spin axis z_W onto y_P.
M0 = rot_x(-math.pi / 2)


def platform_pose(row):
    """(R, p): R = Rz(yaw) Ry(pitch) Rx(roll), p = COM (docs/formats.md)."""
    rot = rot_z(row["yaw"]) @ rot_y(row["pitch"]) @ rot_x(row["roll"])
    return rot, np.array([row["x"], row["y"], row["z"]], float)


def mount_points(geom):
    """b1, b2, b3 in {P}: front steer joint, left and right camber joints."""
    a, b, t, zh = geom["a"], geom["b"], geom["track"], geom["z_h"]
    return [np.array([a, 0.0, -zh]), np.array([-b, t / 2, -zh]),
            np.array([-b, -t / 2, -zh])]


def wheel_frames_platform(geom, row):
    """[(R_PW, p_PW)] of the three wheels in {P}:
    T_PW1 = (Rz(φ1) M0 Rz(α1), b1), T_PWi = (Rx(δi) M0 Rz(αi), b_i + Rx(δi) e_i)
    with e_i = (0, 0, -e) (docs/model.md §1)."""
    b = mount_points(geom)
    offset = np.array([0.0, 0.0, -geom.get("e", 0.0)])
    frames = [(rot_z(row["phi1"]) @ M0 @ rot_z(row["alpha1"]), b[0])]
    for i, (delta, alpha) in enumerate(((row["delta2"], row["alpha2"]),
                                        (row["delta3"], row["alpha3"])), start=1):
        camber = rot_x(delta)
        frames.append((camber @ M0 @ rot_z(alpha), b[i] + camber @ offset))
    return frames


def wheel_frames_world(geom, row):
    rot, pos = platform_pose(row)
    return [(rot @ r_pw, pos + rot @ p_pw) for r_pw, p_pw in wheel_frames_platform(geom, row)]


def torus_grid(geom, n_u=28, n_v=12):
    """Torus points in {W}: c_w(u, v), shape (n_u, n_v, 3)."""
    u = np.linspace(0, 2 * math.pi, n_u)
    v = np.linspace(0, 2 * math.pi, n_v)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    radius = geom["R"] + geom["r"] * np.cos(vv)
    return np.stack([radius * np.cos(uu), radius * np.sin(uu), geom["r"] * np.sin(vv)],
                    axis=-1)


def torus_residual(geom, rot, centre, point):
    """Distance of a world point from the torus surface of a wheel [m]."""
    q = rot.T @ (np.asarray(point, float) - centre)
    return abs(math.hypot(math.hypot(q[0], q[1]) - geom["R"], q[2]) - geom["r"])


def row_at(traj, k):
    return {name: float(values[k]) for name, values in traj.items()
            if not isinstance(values, list)}


def finite_pose(row):
    names = ("x", "y", "z", "roll", "pitch", "yaw") + JOINTS
    return all(math.isfinite(row.get(n, math.nan)) for n in names)


def terrain_normal(spec, x, y, height):
    """Unit terrain normal (-h_x, -h_y, 1)/w by central differences."""
    step = 1e-5
    hx = (height(spec, np.array(x + step), np.array(y)) -
          height(spec, np.array(x - step), np.array(y))) / (2 * step)
    hy = (height(spec, np.array(x), np.array(y + step)) -
          height(spec, np.array(x), np.array(y - step))) / (2 * step)
    n = np.array([-float(hx), -float(hy), 1.0])
    return n / np.linalg.norm(n)


def contact_force_world(rot_w, normal, n_force, t_lon, t_lat):
    """F = N n_g + t_lon l + t_lat (n_g × l), l = unit(a_spin × n_g)
    (docs/model.md, quasi-static outputs)."""
    spin = rot_w[:, 2]
    lon = np.cross(spin, normal)
    norm = np.linalg.norm(lon)
    if norm < 1e-12:
        return n_force * normal
    lon /= norm
    return n_force * normal + t_lon * lon + t_lat * np.cross(normal, lon)
