"""The paper's equations as its readers find them in the published paper (Jerome & Di Pierro, J. Fluid Mech.
2018; README gives the full reference): numbered by section, as the journal prints them, (2.12) the twelfth
numbered row of section 2; an equation of two rows has two numbers.

``EQUATIONS`` maps the accepted manuscript's LaTeX labels, which no reader can look up and which nothing this
package writes may show, to (numbers, short name)."""
from __future__ import annotations

EQUATIONS: dict[str, tuple[tuple[str, ...], str]] = {
    # 2  Governing equations
    "MuI": (("2.1",), "the mu(I) law"),
    "ConstitutiveLawMuI": (("2.2",), "the constitutive law"),
    "ViscosityMuI": (("2.3",), "the effective viscosity"),
    "InertialNumberMuI": (("2.4",), "the inertial number"),
    "StokesEqn1": (("2.5",), "the x momentum balance"),
    "StokesEqn2": (("2.6",), "the hydrostatic pressure"),
    "InitStokesEqn": (("2.7",), "the initial state tau = mu_s p"),
    "BCStokesEqn": (("2.8", "2.9"), "the wall's pressure and friction"),
    "MuSteadyState": (("2.10",), "the steady friction profile"),
    "ShearLayerThickness": (("2.11",), "the steady layer depth delta_s"),
    "IreWritten": (("2.12",), "the mu(I) law solved for du/dy"),
    "step2StokesEqn": (("2.13",), "its time derivative"),
    "GranularStokesEqnDIM": (("2.14",), "the stress diffusion equation, dimensional"),
    "GranularStokesEqn": (("2.15",), "the stress diffusion equation"),
    "DispersionEquationHadamard": (("2.16",), "the well-posedness dispersion relation"),
    # 3  Unsteady solutions and their characteristics
    "GranularStokesEqn_mu": (("3.1",), "the diffusion equation for mu"),
    "GranularStokesEqn_muLINshort": (("3.2",), "its short-time form"),
    "SolutionSS": (("3.3",), "the short-time erfc solution"),
    "GranularStokesEqn_muLINlong": (("3.4",), "the long-time form in y^"),
    "SolutionLONG": (("3.5",), "the long-time WKB series"),
    "SolutionLONG_constants": (("3.6", "3.7"), "the WKB series' constants"),
    "nonDIMv": (("3.8",), "the velocity scale U"),
    "nonDIMmu": (("3.9",), "the normalised friction mu~"),
    "IreWrittenNonDim": (("3.10",), "the dimensionless velocity gradient"),
    "UwallInt": (("3.11",), "the steady wall speed's integral"),
    "Uwall_asymp": (("3.12",), "the steady wall speed's asymptote"),
    "Uwall_muS": (("3.13",), "the steady wall speed near yield"),
    "GranularStokesEqn_muBIS": (("3.14",), "the imposed-speed equation for mu~"),
    "GranularStokesEqn_muBIS_BCs": (("3.15",), "the imposed speed's integral condition"),
    "TimeScaleMu": (("3.16",), "the 1/sqrt(t~) decay of mu_w"),
    "TimeScaleMuD": (("3.17",), "the time scale t~_mud"),
    "TimeScaleMuW": (("3.18",), "the time scale t~_muw"),
    "GranularStokesEqn_muBIS_ShortTime": (("3.19",), "the imposed-speed equation at short times"),
    "muShortTime_VelocityImposed": (("3.20",), "the imposed-speed erfc profile"),
}


def eq(label: str, named: bool = False) -> str:
    """The citation of the equation with LaTeX label ``label``: 'eq. (3.12)', 'eqs. (2.8)-(2.9)'; ``named``
    adds its short name: 'eq. (3.12), the steady wall speed's asymptote'."""
    numbers, name = EQUATIONS[label]
    cited = f"eq. ({numbers[0]})" if len(numbers) == 1 else f"eqs. ({numbers[0]})-({numbers[-1]})"
    return f"{cited}, {name}" if named else cited
