"""The table as an FMI 2.0 FMU (``isolator fmu``): Model Exchange and Co-Simulation, the exact model in C.

The contract is ``docs/scenario-format.md``, section "The table as an FMU". The equations are casadi's code
generated from :mod:`isolator.fmu.functions`; the rest of the C (the profiles as functions of time, Newton's
method for the static equilibrium at initialisation, RK4 steps in ``doStep``, the FMI API) is the template
``templates/plant.c.j2``, rendered with the scenario's numbers; ``modelDescription.xml`` is
``templates/modelDescription.xml.j2``. Names reach both only through
:func:`isolator.numerics.rendering.escape_name`.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import casadi as ca
import numpy as np

from isolator.errors import ParameterError
from isolator.fmu.functions import PlantFunctions, plant_functions, state_nominals
from isolator.fmu.package import FmuVariable, build_fmu, c_compiler, model_identifier
from isolator.fmu.parameter_checks import parameter_checks
from isolator.fmu.units import parameter_unit, sensor_unit, state_units
from isolator.model.names import expand_changes, resolve
from isolator.model.parameters import ParameterLayout
from isolator.numerics.rendering import render
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.scenario.profiles import PiecewisePolynomialProfile, Profile, SineProfile
from isolator.simulation.simulator import Simulator
from isolator.simulation.stepping import STEP_ANGLE, fastest_rate

__all__ = ["write_fmu"]

#: the communication step the contract's accuracy is stated for [s]
COMMUNICATION_STEP = 1e-3
#: doStep's RK4 steps are this much shorter than the simulator's rule (|lambda| h <= STEP_ANGLE, the
#: actuators' lags among the eigenvalues): 4^4 = 256 times less error, for the contract's 1e-6 of the peak of
#: the smallest signal (z, rz) where the table's motions couple
REFINE = 4


def _profile_rows(profiles: Sequence[tuple[str, Profile | None]]) -> tuple[list[dict[str, Any]], list[float],
                                                                            list[float]]:
    """The C table of profiles: one row each, and the knots and coefficients they index."""
    rows: list[dict[str, Any]] = []
    knots: list[float] = []
    coefs: list[float] = []
    for what, pr in profiles:
        row: dict[str, Any] = {"what": what, "kind": 0, "pieces": 0, "order": 0, "knot_at": 0, "coef_at": 0,
                               "amplitude": 0.0, "omega": 0.0, "phase": 0.0, "offset": 0.0, "t0": 0.0}
        if isinstance(pr, PiecewisePolynomialProfile):
            c = np.asarray(pr.coefficients, dtype=float)
            row |= {"kind": 1, "pieces": c.shape[0], "order": c.shape[1], "knot_at": len(knots),
                    "coef_at": len(coefs)}
            knots += [float(k) for k in pr.knots]
            coefs += [float(v) for v in c.ravel()]
        elif isinstance(pr, SineProfile):
            row |= {"kind": 2, "amplitude": pr.amplitude, "omega": pr.omega, "phase": pr.phase,
                    "offset": pr.offset, "t0": pr.t0}
        elif pr is not None:
            raise ParameterError(f"{what}: a profile of type {type(pr).__name__} has no C form")
        rows.append(row)
    return rows, knots, coefs


def _tunable(layout: ParameterLayout, names: Sequence[str], key: str) -> list[tuple[str, tuple[int, ...]]]:
    """Each name and the parameter entries it sets (errors name ``key``)."""
    out = []
    for name in names:
        if not isinstance(name, str):
            raise ParameterError(f"{key}: names must be strings, got {name!r}")
        column = resolve(layout, name, "set", f"{key} {name!r}")
        out.append((name, column.entries))
    if len({n for n, _ in out}) != len(out):
        raise ParameterError(f"{key}: a name is given twice")
    return out


def _generated(functions: PlantFunctions, identifier: str) -> tuple[str, str, list[dict[str, Any]]]:
    """casadi's C for the functions (the step only with lagged actuators), its header, and each function's C name
    and sizes."""
    z = ca.SX.sym("z", functions.static.size1_in(0))
    c, p = ca.SX.sym("c", functions.static.size1_in(1)), ca.SX.sym("p", functions.static.size1_in(2))
    r, jac = functions.static(z, c, p)
    static = ca.Function("static", [z, c, p], [r, ca.densify(jac)])
    named = {"ODE": functions.ode, "OUTPUTS": functions.outputs, "STATIC": static, "POSE": functions.pose}
    if functions.lagged:  # doStep's step with the lags taken exactly (without lags, RK4 in C on the ODE)
        named |= {"STEP": functions.step, "STEP_CUT": functions.step_cut, "CROSSING": functions.crossing,
                  "LAG_WEIGHTS": functions.weights}
    generator = ca.CodeGenerator(f"{identifier}_model.c", {"with_header": True})
    rows = []
    for macro, f in named.items():
        sx = f.sx_in()
        fn = ca.Function(f"{identifier}_{macro.lower()}", sx, [ca.densify(o) for o in f.call(sx)])
        generator.add(fn)
        rows.append({"macro": macro, "name": fn.name(), "arg": fn.n_in(), "res": fn.n_out(), "iw": fn.sz_iw(),
                     "w": fn.sz_w(), "sz_arg": fn.sz_arg(), "sz_res": fn.sz_res()})
    with tempfile.TemporaryDirectory() as tmp:
        generator.generate(tmp + os.sep)
        source = Path(tmp, f"{identifier}_model.c").read_text()
        header = Path(tmp, f"{identifier}_model.h").read_text()
    return source, header, rows


def _variables(scenario: Scenario, functions: PlantFunctions, inputs_mode: bool,
               tunable: list[tuple[str, tuple[int, ...]]], p: np.ndarray, nominals: np.ndarray
               ) -> tuple[list[FmuVariable], int, list[float]]:
    """The FMU's variables in value-reference order (outputs, inputs, parameters, states, their derivatives,
    time), each with its SI unit; the number of outputs and the inputs' start values."""
    variables: list[FmuVariable] = []
    outputs = [(n, "m", "mass centre displacement [m]") for n in ("x", "y", "z")]
    outputs += [(n, "rad", "rotation vector [rad]") for n in ("rx", "ry", "rz")]
    outputs += [(f"s:{s.name}", sensor_unit(s), f"sensor reading [{sensor_unit(s)}], noise-free")
                for s in scenario.sensors]
    outputs += [(f"{pt.name}:{a}", "m", "point displacement [m]") for pt in scenario.points for a in "xyz"]
    if functions.model.layout.flexible is not None:
        outputs += [(f"{pt.name}:e{a}", "m", "the top's elastic translation at the point, table axes [m]")
                    for pt in scenario.points for a in "xyz"]
    if not inputs_mode:
        outputs += [(f"q:{c.name}", "m", "carriage position along its axis [m] (its profile)")
                    for c in scenario.carriages]
    for name, unit, text in outputs:
        variables.append(FmuVariable(name, len(variables), "output", description=text, unit=unit))
    inputs = [(f"f:{a.name}", 0.0, "N", "actuator command [N]") for a in scenario.actuators]
    inputs += [(f"floor:{a}", 0.0, "m", "floor translation [m]") for a in "xyz"]
    inputs += [(f"floor:v{a}", 0.0, "m/s", "floor velocity [m/s]") for a in "xyz"]
    if inputs_mode:
        q0 = scenario.initial_positions()
        for kind, unit in (("q", "m"), ("v", "m/s"), ("a", "m/s2")):
            inputs += [(f"{kind}:{c.name}", float(q0[i]) if kind == "q" else 0.0, unit, f"carriage {kind} [{unit}]")
                       for i, c in enumerate(scenario.carriages)]
    for name, value, unit, text in inputs:
        variables.append(FmuVariable(name, len(variables), "input", description=text, start=value, unit=unit))
    for name, entries in tunable:
        variables.append(FmuVariable(name, len(variables), "parameter", "fixed", "parameter (as --set)",
                                     "exact", float(p[entries[0]]), unit=parameter_unit(name)))
    first_state = len(variables) + 1
    units, rates = state_units(functions.model.n_states, len(functions.lagged))
    for k in range(nominals.size):
        variables.append(FmuVariable(f"state[{k}]", len(variables), "local", description="model state",
                                     initial="calculated", nominal=float(nominals[k]), unit=units[k]))
    for k in range(nominals.size):
        variables.append(FmuVariable(f"der(state[{k}])", len(variables), "local", initial="calculated",
                                     derivative=first_state + k, unit=rates[k]))
    variables.append(FmuVariable("time", len(variables), "independent", unit="s"))
    if len({v.name for v in variables}) != len(variables):
        raise ParameterError("scenario: two of its names make the same FMU variable name")

    return variables, len(outputs), [v for _, v, _, _ in inputs]


def write_fmu(scenario: Scenario, out: str | Path, carriages: Literal["profiles", "inputs"] = "profiles",
              parameters: Sequence[str] = (), changes: Mapping[str, float] | None = None,
              keys: Mapping[str, str] | None = None) -> Path:
    """Write the table of ``scenario`` as an FMI 2.0 FMU (Model Exchange and Co-Simulation).

    Parameters
    ----------
    scenario : Scenario
    out : str or Path
        The ``.fmu`` file.
    carriages : {"profiles", "inputs"}
        The carriages move by the scenario's profiles (functions of the FMU's time), or by the inputs
        ``q:``, ``v:``, ``a:<carriage>``.
    parameters : sequence of str
        Names as ``isolator sweep --set`` takes them, each a parameter of the FMU.
    changes : mapping of str to float, optional
        Values changed in the scenario before it is exported (as ``--set``).
    keys : mapping of str to str, optional
        How errors name the arguments ``out``, ``parameters``, ``changes`` (default: so; the command line
        passes its options' names).

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    ParameterError
        A bad option (naming it), no C compiler.
    UnstableTableError
        The table has no stable equilibrium.
    """
    if carriages not in ("profiles", "inputs"):
        raise ParameterError(f"carriages: must be 'profiles' or 'inputs', got {carriages!r}")
    out = Path(out)
    c_compiler()  # before any work
    sim = Simulator(scenario)
    names = {"out": "out", "parameters": "parameters", "changes": "changes", **(keys or {})}
    expanded = expand_changes(sim.layout, changes, names["changes"])
    p = sim.layout.with_changes(sim.parameters, expanded, names["changes"])  # type: ignore[arg-type]
    tunable = _tunable(sim.layout, list(parameters), names["parameters"])  # the same names as the FMU's model
    sim.check_tipping(p)
    start, end = sim.equilibria(p)
    inputs_mode = carriages == "inputs"
    functions = plant_functions(scenario, positions=not inputs_mode)
    model, layout = functions.model, functions.model.layout
    omega = max(fastest_rate(scenario, max(start.max_frequency, end.max_frequency if end is not None else 0.0)),
                1e-9)  # the simulator's rule (a lag costs no step: the step function takes it exactly)
    max_step = min(COMMUNICATION_STEP, STEP_ANGLE / omega / REFINE)
    floor = scenario.ground.motion if scenario.ground is not None else {}
    profiles: list[tuple[str, Profile | None]] = [] if inputs_mode else [
        (f"carriages[{i}] {c.name}", c.profile) for i, c in enumerate(scenario.carriages)]
    profiles += [(f"floor {axis}", floor.get(axis)) for axis in SIGNALS]
    rows, knots, coefs = _profile_rows(profiles)
    identifier = model_identifier(out.stem)
    casadi_source, casadi_header, sizes = _generated(functions, identifier)
    rest = np.concatenate([start.state, np.zeros(len(functions.lagged))])

    nominals = state_nominals(functions, rest)
    variables, n_outputs, input_starts = _variables(scenario, functions, inputs_mode, tunable, p, nominals)
    entry_at, entries = [0], list[int]()
    for _, matched in tunable:
        entries += list(matched)
        entry_at.append(len(entries))
    breakpoints = sorted(set() if inputs_mode else {b for c in scenario.carriages for b in c.profile.breakpoints}
                         | (set(scenario.ground.breakpoints) if scenario.ground is not None else set()))
    context = {
        "identifier": identifier, "scenario": scenario.name, "guid": "@GUID@", "nx": functions.n_states,
        "nu": layout.input_size, "np": layout.size, "nz": model.n_static, "ny": n_outputs, "ni": len(input_starts),
        "nq": len(tunable), "nc": len(scenario.carriages), "na": len(scenario.actuators),
        "breakpoints": [b for b in breakpoints if math.isfinite(b)], "carriage_inputs": inputs_mode,
        "max_step": max_step, "functions": sizes, "max_arg": max(r["sz_arg"] for r in sizes),
        "max_res": max(r["sz_res"] for r in sizes), "max_iw": max(r["iw"] for r in sizes),
        "max_w": max(r["w"] for r in sizes), "knots": knots, "coefs": coefs, "profiles": rows,
        "parameters": [float(v) for v in p], "entry_at": entry_at, "entries": entries,
        "nominals": [float(v) for v in nominals], "rest_guess": [float(v) for v in start.pose],
        "input_starts": input_starts, "input_names": [v.name for v in variables if v.causality == "input"],
        "lagged": bool(functions.lagged), "nw": functions.weights.numel_out(0),
        **parameter_checks(sim.layout, tunable),
    }
    sources = {
        f"{identifier}.c": render("isolator.fmu", "templates/plant.c.j2", **context),
        f"{identifier}_model.c": render("isolator.fmu", "templates/model.c.j2", identifier=identifier,
                                        casadi=casadi_source),
        f"{identifier}_model.h": casadi_header,
    }
    stop = scenario.simulation.duration
    return build_fmu(out, identifier, scenario.name, f"isolation table {scenario.name} (isolator)", variables,
                     sources, me=True, cs=True, step=COMMUNICATION_STEP, stop_time=stop, interpolates=True,
                     key=names["out"])


check_public(globals())
