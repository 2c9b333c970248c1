#!/usr/bin/env python3
"""Independent check of jointsim's robot data files (numpy + PyYAML only; no jointsim code).

Run from anywhere:  python3 tests/data/check_robot_files.py
Needs: numpy, pyyaml (pip install numpy pyyaml). Not part of the build. Exit code 0 = all checks passed.

(a) config/robots/ur5.yaml: TCP by [Raviola2023, §2.6, eq. 8] (DH + Hayati beta, theta = q + offset) at
    q = 0 and q = (0, -pi/2, 0, -pi/2, 0, 0) against our FK test vectors for [Raviola2023, Table 4]
    (tolerance 1e-6 m).
    config/robots/ur5.urdf: parsed, inertias positive definite, tool0 pose against the nominal UR5 DH model
    (base_link = UR base frame rotated by pi about z) at several q.
(b) tests/data/planar2.urdf, planar2_tree.yaml, planar2_dh.yaml: tip position, joint-space inertia matrix M(q)
    and gravity torque g(q) at 3 configurations; the three files must agree to 1e-12, and agree with the
    closed-form expressions. The numbers are printed for use as C++ test references.
(c) config/robots/irb140.yaml: flange (clamp point) at q = 0 must be (0.515, 0.712, 0) m.

Conventions of the printed numbers: M(q) from T = 1/2 qd^T M(q) qd (armature 0). g(q) is the gravity term of
M qdd + C qd + g(q) = tau, i.e. the joint torque that holds the arm still: g = -sum_i m_i Jv_i^T gravity.
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
FAILURES = []


def check(cond, msg):
    print(("  ok    " if cond else "  FAIL  ") + msg)
    if not cond:
        FAILURES.append(msg)


# ----------------------------------------------------------------------------------------------------------
# small rigid-body helpers
# ----------------------------------------------------------------------------------------------------------
def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rpy_to_R(rpy):
    """URDF rpy: fixed-axis roll (x), pitch (y), yaw (z) -> R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    return rz(y) @ ry(p) @ rx(r)


def axis_angle(axis, q):
    k = np.asarray(axis, float)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(q) * K + (1 - math.cos(q)) * K @ K


def hom(R=None, p=None):
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def inertia6_to_mat(v):
    ixx, iyy, izz, ixy, ixz, iyz = [float(x) for x in v]
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def inertia_ok(m, I):
    """mass > 0 -> positive definite (and triangle inequality); mass == 0 -> all zeros allowed."""
    if m == 0:
        return True
    ev = np.linalg.eigvalsh(I)
    tri = ev[0] + ev[1] >= ev[2] - 1e-15
    return bool(np.all(ev > 0) and tri and np.allclose(I, I.T))


# ----------------------------------------------------------------------------------------------------------
# generic dynamics from world-frame quantities (Lagrangian: M = sum m Jv^T Jv + Jw^T I Jw)
# ----------------------------------------------------------------------------------------------------------
class Kin:
    """Result of a forward-kinematics pass.

    joints: list of (type, world axis, world point) for the n joint coordinates, in q order.
    bodies: list of (mass, world CoM, world inertia about CoM, set of ancestor joint indices).
    frames: dict name -> 4x4 world pose.
    """

    def __init__(self):
        self.joints, self.bodies, self.frames = [], [], {}


def mass_matrix_and_gravity(kin, gravity):
    n = len(kin.joints)
    M = np.zeros((n, n))
    g = np.zeros(n)
    for m, c, Iw, anc in kin.bodies:
        if m == 0.0:
            continue
        Jv = np.zeros((3, n))
        Jw = np.zeros((3, n))
        for j in anc:
            typ, z, p = kin.joints[j]
            if typ == "prismatic":
                Jv[:, j] = z
            else:
                Jv[:, j] = np.cross(z, c - p)
                Jw[:, j] = z
        M += m * Jv.T @ Jv + Jw.T @ Iw @ Jw
        g += -m * Jv.T @ np.asarray(gravity, float)
    return M, g


# ----------------------------------------------------------------------------------------------------------
# DH-Hayati (jointsim YAML, convention dh_hayati), [Raviola2023, §2.6, eqs. 8–9]
# ----------------------------------------------------------------------------------------------------------
def A_eq8(a, alpha, beta, d, theta):
    """The 4x4 matrix of eq. 8, written out as printed in [Raviola2023, §2.6]."""
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    cb, sb = math.cos(beta), math.sin(beta)
    return np.array([
        [ct * cb - st * sa * sb, -st * ca, ct * sb + st * sa * cb, a * ct],
        [st * cb + ct * sa * sb, ct * ca, st * sb - ct * sa * cb, a * st],
        [-ca * sb, sa, ca * cb, d],
        [0, 0, 0, 1]])


def A_product(a, alpha, beta, d, theta):
    """Transl(z,d) Rot(z,theta) Transl(x,a) Rot(x,alpha) Rot(y,beta)."""
    return hom(p=[0, 0, d]) @ hom(rz(theta)) @ hom(p=[a, 0, 0]) @ hom(rx(alpha)) @ hom(ry(beta))


def load_yaml(path):
    with open(path) as f:
        return yaml.safe_load(f)


DH_TOP = {"name", "gravity", "convention", "dh_units", "links", "tool"}
DH_LINK = {"name", "joint", "mass", "com", "inertia"}
DH_JOINT = {"name", "type", "a", "alpha", "beta", "d", "theta", "armature", "limits"}
TREE_TOP = {"name", "gravity", "convention", "links", "joints"}
TREE_LINK = {"name", "mass", "com", "inertia"}
TREE_JOINT = {"name", "type", "parent", "child", "origin", "axis", "armature", "limits"}
LIMITS = {"lower", "upper", "velocity", "effort"}


def check_keys(doc, label):
    ok = True
    if doc["convention"] == "dh_hayati":
        ok &= set(doc) <= DH_TOP
        for L in doc["links"]:
            ok &= set(L) <= DH_LINK and set(L["joint"]) <= DH_JOINT
            ok &= set(L["joint"].get("limits", {})) <= LIMITS
            ok &= inertia_ok(float(L["mass"]), inertia6_to_mat(L["inertia"]))
        if "tool" in doc:
            ok &= set(doc["tool"]) <= {"name", "xyz", "rpy"}
        ok &= set(doc.get("dh_units", {})) <= {"length", "angle"}
    else:
        ok &= set(doc) <= TREE_TOP
        for L in doc["links"]:
            ok &= set(L) <= TREE_LINK
            ok &= inertia_ok(float(L["mass"]), inertia6_to_mat(L["inertia"]))
        for J in doc["joints"]:
            ok &= set(J) <= TREE_JOINT and set(J.get("limits", {})) <= LIMITS
            ok &= set(J["origin"]) <= {"xyz", "rpy"}
    check(ok, f"{label}: only known keys; inertias valid (PD for mass > 0)")


class DHModel:
    def __init__(self, doc):
        units = doc.get("dh_units", {}) or {}
        ls = {"m": 1.0, "mm": 1e-3}[units.get("length", "m")]
        an = {"rad": 1.0, "deg": math.pi / 180}[units.get("angle", "rad")]
        self.gravity = np.asarray(doc["gravity"], float)
        self.rows, self.inert, self.jtypes = [], [], []
        for L in doc["links"]:
            J = L["joint"]
            self.rows.append((J["a"] * ls, J["alpha"] * an, J["beta"] * an, J["d"] * ls, J["theta"] * an))
            self.jtypes.append(J["type"])
            self.inert.append((float(L["mass"]), np.asarray(L["com"], float), inertia6_to_mat(L["inertia"])))
        tool = doc.get("tool")
        self.tool_name = tool["name"] if tool else None
        self.T_tool = hom(rpy_to_R(tool.get("rpy", [0, 0, 0])), tool.get("xyz", [0, 0, 0])) if tool else None

    def fk(self, q, use_product=False):
        kin = Kin()
        T = np.eye(4)
        for i, ((a, al, be, d, th), typ) in enumerate(zip(self.rows, self.jtypes)):
            kin.joints.append((typ, T[:3, 2].copy(), T[:3, 3].copy()))   # joint i axis: z_{i-1} at o_{i-1}
            if typ == "prismatic":
                d, theta = d + q[i], th
            else:
                theta = th + q[i]
            A = A_product(a, al, be, d, theta) if use_product else A_eq8(a, al, be, d, theta)
            T = T @ A
            m, c, Ic = self.inert[i]
            R = T[:3, :3]
            kin.bodies.append((m, T[:3, :3] @ c + T[:3, 3], R @ Ic @ R.T, set(range(i + 1))))
        kin.frames["last"] = T
        if self.T_tool is not None:
            kin.frames[self.tool_name] = T @ self.T_tool
        return kin


# ----------------------------------------------------------------------------------------------------------
# trees: jointsim YAML (convention tree) and URDF
# ----------------------------------------------------------------------------------------------------------
class TreeModel:
    """links: name -> (mass, com in link frame, I about com in link frame);
    joints: list of dict(name, type, parent, child, T_origin, axis)."""

    def __init__(self, links, joints, gravity):
        self.links, self.joints_all, self.gravity = links, joints, np.asarray(gravity, float)
        children = {j["child"] for j in joints}
        self.root = next(n for n in links if n not in children)
        self.moving = [j for j in joints if j["type"] != "fixed"]   # q order = order of appearance

    @staticmethod
    def from_yaml(doc):
        links = {L["name"]: (float(L["mass"]), np.asarray(L["com"], float), inertia6_to_mat(L["inertia"]))
                 for L in doc["links"]}
        joints = []
        for J in doc["joints"]:
            o = J.get("origin", {})
            joints.append(dict(name=J["name"], type=J["type"], parent=J["parent"], child=J["child"],
                               T_origin=hom(rpy_to_R(o.get("rpy", [0, 0, 0])), o.get("xyz", [0, 0, 0])),
                               axis=np.asarray(J.get("axis", [1, 0, 0]), float)))
        return TreeModel(links, joints, doc["gravity"])

    @staticmethod
    def from_urdf(path, gravity=(0, 0, -9.81)):
        root = ET.parse(path).getroot()
        vec = lambda s, default: np.array([float(x) for x in s.split()]) if s is not None else np.array(default, float)
        links = {}
        for L in root.findall("link"):
            inl = L.find("inertial")
            if inl is None:
                links[L.get("name")] = (0.0, np.zeros(3), np.zeros((3, 3)))
                continue
            m = float(inl.find("mass").get("value"))
            o = inl.find("origin")
            xyz = vec(o.get("xyz") if o is not None else None, [0, 0, 0])
            R = rpy_to_R(vec(o.get("rpy") if o is not None else None, [0, 0, 0]))
            i = inl.find("inertia")
            I = inertia6_to_mat([i.get(k, "0") for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")])
            links[L.get("name")] = (m, xyz, R @ I @ R.T)
        joints = []
        for J in root.findall("joint"):
            o = J.find("origin")
            xyz = vec(o.get("xyz") if o is not None else None, [0, 0, 0])
            rpy = vec(o.get("rpy") if o is not None else None, [0, 0, 0])
            ax = J.find("axis")
            joints.append(dict(name=J.get("name"), type=J.get("type"), parent=J.find("parent").get("link"),
                               child=J.find("child").get("link"), T_origin=hom(rpy_to_R(rpy), xyz),
                               axis=vec(ax.get("xyz") if ax is not None else None, [1, 0, 0])))
        return TreeModel(links, joints, gravity)

    def fk(self, q):
        kin = Kin()
        T = {self.root: np.eye(4)}
        anc = {self.root: set()}
        qidx = {j["name"]: k for k, j in enumerate(self.moving)}
        kin.joints = [None] * len(self.moving)
        pending = list(self.joints_all)
        while pending:   # process joints whose parent pose is known
            progress = False
            for j in list(pending):
                if j["parent"] not in T:
                    continue
                Tj = T[j["parent"]] @ j["T_origin"]
                a = set(anc[j["parent"]])
                if j["type"] == "fixed":
                    Tc = Tj
                else:
                    k = qidx[j["name"]]
                    u = j["axis"] / np.linalg.norm(j["axis"])
                    kin.joints[k] = ("prismatic" if j["type"] == "prismatic" else "revolute",
                                     Tj[:3, :3] @ u, Tj[:3, 3].copy())
                    a.add(k)
                    Tc = Tj @ (hom(p=u * q[k]) if j["type"] == "prismatic" else hom(axis_angle(u, q[k])))
                T[j["child"]], anc[j["child"]] = Tc, a
                pending.remove(j)
                progress = True
            assert progress, "disconnected tree"
        for name, (m, c, Ic) in self.links.items():
            if name == self.root:
                continue   # fixed to the world: does not enter the dynamics
            R = T[name][:3, :3]
            kin.bodies.append((m, R @ c + T[name][:3, 3], R @ Ic @ R.T, anc[name]))
        kin.frames = T
        return kin


def fmt(v):
    return np.array2string(np.asarray(v), precision=15, floatmode="maxprec", separator=", ",
                           max_line_width=200, suppress_small=False)


# ----------------------------------------------------------------------------------------------------------
def part_a():
    print("\n(a) UR5")
    doc = load_yaml(os.path.join(ROOT, "config/robots/ur5.yaml"))
    check_keys(doc, "ur5.yaml")
    ur5 = DHModel(doc)
    cases = [((0, 0, 0, 0, 0, 0), (-0.816942, -0.193425, -0.004279)),
             ((0, -math.pi / 2, 0, -math.pi / 2, 0, 0), (0.001371, -0.191476, 1.001153))]
    for q, ref in cases:
        kin = ur5.fk(np.array(q, float))
        p = kin.frames["tool0"][:3, 3]
        p2 = ur5.fk(np.array(q, float), use_product=True).frames["tool0"][:3, 3]
        print(f"  q = {fmt(q)}  TCP = {fmt(p)}")
        check(np.max(np.abs(p - np.array(ref))) <= 1e-6, f"ur5.yaml TCP at q={q} matches {ref} to 1e-6")
        check(np.max(np.abs(p - p2)) < 1e-14, "eq. 8 matrix == product Transl(z,d)Rot(z,th)Transl(x,a)Rot(x,al)Rot(y,be)")
    # informational: M and g of ur5.yaml (no armature) at the two test configurations
    for q, _ in cases:
        M, g = mass_matrix_and_gravity(ur5.fk(np.array(q, float)), ur5.gravity)
        print(f"  ur5.yaml q = {fmt(q)}\n    diag M = {fmt(np.diag(M))}\n    g = {fmt(g)}")

    # URDF: standard ROS-Industrial UR5; compare with the nominal UR5 DH model ([URDH])
    urdf = TreeModel.from_urdf(os.path.join(ROOT, "config/robots/ur5.urdf"))
    check(all(inertia_ok(m, I) for m, _, I in urdf.links.values()), "ur5.urdf: inertias PD for every link with mass > 0")
    check([j["name"] for j in urdf.moving] == ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                                "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"],
          "ur5.urdf: joint names/order")
    nominal = [(0, math.pi / 2, 0.089159), (-0.425, 0, 0), (-0.39225, 0, 0), (0, math.pi / 2, 0.10915),
               (0, -math.pi / 2, 0.09465), (0, 0, 0.0823)]   # (a, alpha, d)

    def nominal_fk(q):
        T = np.eye(4)
        for (a, al, d), qi in zip(nominal, q):
            T = T @ A_product(a, al, 0, d, qi)
        return T

    p0 = urdf.fk(np.zeros(6)).frames["tool0"][:3, 3]
    print(f"  ur5.urdf tool0 at q = 0 (base_link): {fmt(p0)}")
    check(np.max(np.abs(p0 - np.array([0.81725, 0.19145, -0.005491]))) < 1e-12, "ur5.urdf tool0 at q=0")
    rng = np.random.default_rng(1)
    qs = [np.zeros(6), np.array([0, -math.pi / 2, 0, -math.pi / 2, 0, 0])] + [rng.uniform(-math.pi, math.pi, 6) for _ in range(5)]
    err = 0.0
    for q in qs:
        T_urdf = hom(rz(math.pi)) @ urdf.fk(q).frames["tool0"]   # UR base frame = base_link rotated by pi
        err = max(err, np.max(np.abs(T_urdf - nominal_fk(q))))
    check(err < 1e-9, f"ur5.urdf tool0 pose == nominal UR5 DH (after base rotation pi), max err {err:.2e}")


# ----------------------------------------------------------------------------------------------------------
def part_b():
    print("\n(b) planar2 cross-format check")
    d = os.path.join(ROOT, "tests/data")
    tree_doc = load_yaml(os.path.join(d, "planar2_tree.yaml"))
    dh_doc = load_yaml(os.path.join(d, "planar2_dh.yaml"))
    check_keys(tree_doc, "planar2_tree.yaml")
    check_keys(dh_doc, "planar2_dh.yaml")
    models = {
        "urdf": TreeModel.from_urdf(os.path.join(d, "planar2.urdf"), gravity=(0, 0, -9.81)),
        "tree": TreeModel.from_yaml(tree_doc),
        "dh": DHModel(dh_doc),
    }
    check(list(tree_doc["gravity"]) == [0, 0, -9.81] and list(dh_doc["gravity"]) == [0, 0, -9.81],
          "YAML gravity is [0, 0, -9.81]")
    l1, l2, c1, c2, m1, m2, g0 = 0.7, 0.5, 0.3, 0.2, 3.0, 2.0, 9.81

    def closed_form(q):
        q1, q2 = q
        r = l1 + l2 * math.cos(q2)
        tip = np.array([math.cos(q1) * r, math.sin(q1) * r, l2 * math.sin(q2)])
        M11 = 0.055 + m1 * c1 ** 2 + m2 * (l1 + c2 * math.cos(q2)) ** 2 \
            + 0.012 * math.sin(q2) ** 2 + 0.02 * math.cos(q2) ** 2
        M = np.array([[M11, 0.0], [0.0, 0.03 + m2 * c2 ** 2]])
        g = np.array([0.0, m2 * g0 * c2 * math.cos(q2)])
        return tip, M, g

    configs = [np.array([0.0, 0.0]), np.array([0.3, -0.7]), np.array([-1.2, 2.1])]
    for q in configs:
        res = {}
        for name, mdl in models.items():
            kin = mdl.fk(q)
            M, g = mass_matrix_and_gravity(kin, mdl.gravity)
            res[name] = (kin.frames["tip"][:3, 3], M, g, kin.frames["tip"][:3, :3])
        tip, M, g, _ = res["tree"]
        print(f"  q = {fmt(q)} rad")
        print(f"    tip = {fmt(tip)} m")
        print(f"    M   = {fmt(M[0])}\n          {fmt(M[1])} kg m^2")
        print(f"    g   = {fmt(g)} N m")
        for other in ("urdf", "dh"):
            dev = max(np.max(np.abs(a - b)) for a, b in zip(res["tree"], res[other]))
            check(dev < 1e-12, f"tree vs {other}: tip, M, g, tip orientation agree (max dev {dev:.1e})")
        t_cf, M_cf, g_cf = closed_form(q)
        dev = max(np.max(np.abs(tip - t_cf)), np.max(np.abs(M - M_cf)), np.max(np.abs(g - g_cf)))
        check(dev < 1e-12, f"tree vs closed form (max dev {dev:.1e})")
        # gravity = gradient of the potential energy (finite differences)
        def V(qq):
            return sum(-m * (np.asarray(models["dh"].gravity) @ c) for m, c, _, _ in models["dh"].fk(qq).bodies)
        h = 1e-6
        gfd = np.array([(V(q + h * e) - V(q - h * e)) / (2 * h) for e in np.eye(2)])
        check(np.max(np.abs(gfd - g)) < 1e-7, "g = dV/dq (finite differences)")


# ----------------------------------------------------------------------------------------------------------
def part_c():
    print("\n(c) IRB140")
    doc = load_yaml(os.path.join(ROOT, "config/robots/irb140.yaml"))
    check_keys(doc, "irb140.yaml")
    irb = TreeModel.from_yaml(doc)
    check([j["name"] for j in irb.moving] == [f"joint{i}" for i in range(1, 7)], "irb140: joint names joint1..joint6")
    kin = irb.fk(np.zeros(6))
    p = kin.frames["flange"][:3, 3]
    print(f"  flange at q = 0: {fmt(p)} m")
    check(np.max(np.abs(p - np.array([0.515, 0.712, 0.0]))) < 1e-12, "irb140 flange at q=0 is (0.515, 0.712, 0)")
    check(abs(sum(m for m, _, _ in irb.links.values()) - 98.0) < 1e-12, "irb140 total mass 98 kg")
    for name, ref in (("link1a", (0, 0.1, 0)), ("link2", (0.07, 0.352, 0)), ("link3", (0.07, 0.712, 0)),
                      ("link4", (0.45, 0.712, 0))):
        check(np.allclose(kin.frames[name][:3, 3], ref, atol=1e-12), f"irb140 {name} frame origin at {ref}")
    M, g = mass_matrix_and_gravity(kin, irb.gravity)
    print(f"  q = 0: diag M = {fmt(np.diag(M))}\n         g = {fmt(g)}")


if __name__ == "__main__":
    np.set_printoptions(precision=15)
    part_a()
    part_b()
    part_c()
    print()
    if FAILURES:
        print(f"{len(FAILURES)} check(s) FAILED")
        sys.exit(1)
    print("all checks passed")
