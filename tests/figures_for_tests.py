"""Small figure specs with analytic answers, shared by the physics tests."""


def rod(name, length=1.0, mass=1.0, radius=0.01):
    return {"name": name, "mass": mass, "segment": [[0, 0], [length, 0]], "radius": radius}


def pendulum(n_links=1, length=1.0, mass=1.0, actuated=False, angle=-1.5708, initial=0.0, **joint):
    """A chain hanging from a fixed mount; link 1 points down at q = 0."""
    bodies = [rod("mount", 0.1)] + [rod(f"l{i}", length, mass) for i in range(n_links)]
    joints = []
    for i in range(n_links):
        j = {"name": f"j{i}", "parent": "mount" if i == 0 else f"l{i-1}", "child": f"l{i}",
             "offset": [0, 0] if i == 0 else [length, 0], "angle": angle if i == 0 else 0.0,
             "limits": [-10.0, 10.0], "actuated": actuated, "initial": initial if i == 0 else 0.0}
        if actuated:
            j.update(kp=50.0, kd=2.0, torque_limit=100.0)
        j.update(joint)
        joints.append(j)
    return {"name": f"pendulum{n_links}", "root": {"type": "fixed", "body": "mount", "position": [0, 2.0]},
            "bodies": bodies, "joints": joints}


def box(mass=2.0, half=0.2, z0=0.05):
    """A single planar-root box with contact points at its two bottom corners."""
    return {"name": "box", "root": {"type": "planar", "body": "b", "position": [0.0, z0]},
            "bodies": [{"name": "b", "mass": mass, "shape": "box",
                        "segment": [[-half, 0], [half, 0]], "radius": 0.02}],
            "contacts": [{"name": "left", "body": "b", "position": [-half, 0.0]},
                         {"name": "right", "body": "b", "position": [half, 0.0]}]}


def free_star(actuated=True):
    """Three rods on a planar root (for momentum checks without gravity)."""
    bodies = [rod("core", 0.4, 2.0), rod("a", 0.5, 1.0), rod("b", 0.3, 0.7)]
    joints = [{"name": "ja", "parent": "core", "child": "a", "offset": [0.4, 0], "angle": 0.5,
               "limits": [-3.0, 3.0], "actuated": actuated, "kp": 20.0, "kd": 0.5, "torque_limit": 50.0},
              {"name": "jb", "parent": "a", "child": "b", "offset": [0.5, 0], "angle": -0.7,
               "limits": [-3.0, 3.0], "actuated": actuated, "kp": 20.0, "kd": 0.5, "torque_limit": 50.0}]
    return {"name": "free_star", "root": {"type": "planar", "body": "core", "position": [0.3, 1.0]},
            "bodies": bodies, "joints": joints}
