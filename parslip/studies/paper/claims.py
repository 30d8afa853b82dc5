"""Every quantitative statement of the paper as a claim with a tolerance fixed before any measurement.

Responsible for the claims table of ``parslip paper``: each claim's text, its
source in ``onset-of-slip.tex`` (section and a short quote), the paper's
value, the units, the tolerance (an ``Accept`` object built here, with the
reason it is that wide) and the measurement (``studies.paper.measures``) on a dict of
runs by role; ``evaluate`` turns runs into rows with a verdict.  A claim
whose runs are missing or hold too little is "not measured", which counts
against the share that agrees.

Roles (``parslip.studies.paper.study.ROLES`` makes them): push, pull, shear (T0 to
300 l/c_r: three fronts), push_v0_1e-2, push_v0_1e-4 (the v0 sweep),
push_l300, pull_l300, shear_l300, shear_l500 (Sec. 4.4).  Units: t in
l/c_r, x and slip in l, speeds in c_r, widths in a, stresses in rho c_r^2.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Callable

from ...analysis import slip
from ...analysis.fronts import crack_speed, crossing_time, driven_edge, first_break_time, peak_speed, section_width
from . import measures as measure

AGREES, DISAGREES, NOT_MEASURED = "agrees", "disagrees", "not measured"
VERDICTS = (AGREES, DISAGREES, NOT_MEASURED)


# --- tolerances ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Accept:
    """What a measured value must be for the claim to agree: lo <= value <= hi (either may be None),
    or, with ``target`` and ``abs_tol``/``rel_tol``, each entry of a list within its target."""
    lo: float | None = None
    hi: float | None = None
    target: tuple | None = None
    abs_tol: float | None = None
    rel_tol: float | None = None
    why: str = ""

    @property
    def text(self) -> str:
        if self.target is not None:
            tgt = ", ".join(f"{v:g}" for v in self.target)
            tol = f"{self.rel_tol:.0%}" if self.rel_tol is not None else f"{self.abs_tol:g}"
            return f"{'each ' if len(self.target) > 1 else ''}within {tol} of {tgt}"
        if self.lo is not None and self.lo == self.hi:
            return f"exactly {self.lo:g}"
        if self.lo is not None and self.hi is not None:
            return f"{self.lo:g} to {self.hi:g}"
        if self.lo is not None:
            return f">= {self.lo:g}"
        return f"<= {self.hi:g}"

    def ok(self, value) -> bool:
        if self.target is not None:
            vals = list(value) if isinstance(value, (list, tuple)) else [value]
            if len(vals) != len(self.target):
                return False
            for v, t in zip(vals, self.target):
                tol = self.rel_tol * abs(t) if self.rel_tol is not None else self.abs_tol
                if abs(v - t) > tol + 1e-12:
                    return False
            return True
        v = float(value)
        return (self.lo is None or v >= self.lo - 1e-12) and (self.hi is None or v <= self.hi + 1e-12)


def near(target, rel=None, abs=None, why=""):  # noqa: A002  (abs as a keyword reads like the paper's "within")
    t = tuple(target) if isinstance(target, (list, tuple)) else (target,)
    return Accept(target=t, rel_tol=rel, abs_tol=abs, why=why)


def between(lo, hi, why=""):
    return Accept(lo=lo, hi=hi, why=why)


def at_least(lo, why=""):
    return Accept(lo=lo, why=why)


def at_most(hi, why=""):
    return Accept(hi=hi, why=why)


# --- claims ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Claim:
    key: str                        # slug
    claim: str                      # what the paper states, in words
    source: str                     # section and a short quote from the .tex
    paper: str                      # the paper's value as it gives it
    units: str
    accept: Accept                  # fixed here, before any measurement
    needs: tuple[str, ...]          # run roles the measurement reads
    measure: Callable[[dict], object]

    @property
    def tolerance(self) -> str:
        return self.accept.text + (f" ({self.accept.why})" if self.accept.why else "")


def _missing(value) -> bool:
    if value is None:
        return True
    if isinstance(value, (list, tuple)):
        return not value or any(_missing(v) for v in value)
    try:
        return not math.isfinite(float(value))
    except (TypeError, ValueError):
        return True


def verdict(accept: Accept, value) -> str:
    """agrees / disagrees, or not measured when the value is missing (None, NaN, an empty list)."""
    if _missing(value):
        return NOT_MEASURED
    return AGREES if accept.ok(value) else DISAGREES


def fmt(v) -> str:
    if isinstance(v, (list, tuple)):
        return ", ".join(fmt(x) for x in v) if v else "none"
    if isinstance(v, bool):
        return str(v).lower()
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a" if v is None or math.isnan(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, int):
        return str(v)
    return f"{v:.4g}"


# The runs a claim needs, by role (``parslip.studies.paper.study.ROLES``).
PUSH_RUN = ("push",)
PULL_RUN = ("pull",)
SHEAR_RUN = ("shear",)

# Shared reasons for tolerances.
_TIME3 = "3 %: the paper gives nucleation times to 0.1 l/c_r; 3 % is the project's target for push and pull"
_TIME1 = "1 l/c_r: a tenth of the ~10 l/c_r pulse interval, the precision of times read off Figs. 3 and 5"
_EDGE = "0.05 l: five sites, the width of the edge zone the paper's 'x/l = 0' can mean on a 100-site contact"
_SLOW = "0.1 c_r: 'much lesser than the Rayleigh wave speed', an order of magnitude"
_ALL = "every front: the paper states it of all of them"

CLAIMS: list[Claim] = [
    # --- T- (push), Sec. 3.1 ---------------------------------------------------------------
    Claim("push_first", "T- first nucleation", "Sec. 3.1.3: \"When tc_r/l=5.1, the first interface bond is about "
          "to break\"", "5.1", "l/c_r", near(5.1, rel=0.03, why=_TIME3), PUSH_RUN, lambda r: measure.nucleation_time(r["push"], 0)),
    Claim("push_next", "T- second to fourth nucleations", "Fig. 3 caption: \"5.1 (blue), 15.1 (orange), 25.2 "
          "(green), and 35.1 (brown)\"", "15.1, 25.2, 35.1", "l/c_r", near((15.1, 25.2, 35.1), abs=1.0, why=_TIME1),
          PUSH_RUN, lambda r: measure.nucleation_times(r["push"])[1:4]),
    Claim("push_site", "T- pulses nucleate at the rear edge", "Sec. 3.1: \"starting from the left end of the "
          "block x/l=0\"", "0", "l", at_most(0.05, why=_EDGE), PUSH_RUN, lambda r: measure.nucleation_site(r["push"])),
    Claim("push_direction", "T- pulses run toward x/l = 1", "Sec. 3.1: \"grow by breaking adjacent bonds in the "
          "sliding direction towards x/l=1\"", "all toward 1", "share", at_least(1.0, why=_ALL), PUSH_RUN,
          lambda r: measure.directions(r["push"])),
    Claim("push_count", "T- pulses in 100 l/c_r", "Sec. 3.1.1: \"ten such pulses are seen in this figure\"", "10",
          "pulses", between(9, 11, why="one pulse: the tenth is born near the end of the record"), PUSH_RUN,
          lambda r: len(measure.edge_nucleations(r["push"]))),
    Claim("push_interval", "T- pulse interval", "Sec. 3.1.3 / Fig. 3: nucleations at 5.1, 15.1, 25.2, 35.1", "10.0",
          "l/c_r", near(10.0, rel=0.05, why="5 %: half the spread of the Fig. 3 intervals (10.0-10.1) is far "
          "below it; a reading error of 0.5 l/c_r"), PUSH_RUN, lambda r: measure.interval(r["push"])),
    Claim("push_interval_constant", "T- nucleation frequency nearly constant", "Sec. 3.1.1: \"the frequency at "
          "which pulses are nucleated at x/l=0 ... is nearly constant\"", "nearly constant", "std/mean",
          at_most(0.1, why="10 %: 'nearly constant'"), PUSH_RUN, lambda r: measure.interval_spread(r["push"])),
    Claim("push_slow", "T- pulses far slower than c_r", "Sec. 3.1.1: \"initial velocity much lesser than the "
          "Rayleigh wave speed\"", "<< 1", "c_r", at_most(0.1, why=_SLOW), PUSH_RUN, lambda r: measure.mean_steady_speed(r["push"])),
    Claim("push_constant_speed", "T- pulse speed constant across the contact until the far end",
          "Sec. 3.1.1: \"each pulse propagates at nearly constant speed ... until it reaches the right end\"",
          "nearly constant", "|v2/v1 - 1|", at_most(0.3, why="30 %: 'nearly constant' on a slope read by eye"),
          PUSH_RUN, lambda r: measure.speed_constancy(r["push"])),
    Claim("push_same_speed", "T- all four pulses at nearly the same speed", "Sec. 3.1.2: \"all four pulses travel "
          "at nearly the same speed\"", "nearly the same", "max/min", at_most(1.2, why="20 %: 'nearly the same'"),
          PUSH_RUN, lambda r: measure.speed_spread(r["push"], 4)),
    Claim("push_accel_x", "T- leading pulse accelerates near the far edge", "Sec. 3.1.1: \"begins to accelerate "
          "after x/l=0.7\"; Sec. 3.1.2: \"when its tip reaches ~0.8l\"", "0.7-0.8", "l",
          between(0.65, 0.85, why="the paper's two values, each give or take 0.05 l"), PUSH_RUN, lambda r: measure.accel_x(r["push"])),
    Claim("push_accel_time", "T- leading pulse meets the far boundary at t = 48.0", "Sec. 3.1.3: \"at time "
          "tc_r/l = 48.0 when the leading pulse interacts with the other boundary\"", "48.0", "l/c_r",
          near(48.0, abs=5.0, why="5 l/c_r: half a pulse interval"), PUSH_RUN, lambda r: measure.leading_accel_time(r["push"])),
    Claim("push_trailing_accel", "T- trailing pulses accelerate with the leading one", "Sec. 3.1.2: \"the other "
          "trailing pulses accelerate as well, see the coincident increase in v/c_r\"", "increase", "v after/before",
          at_least(1.2, why="20 %: an increase beyond the frame-to-frame scatter of a local speed"), PUSH_RUN,
          lambda r: measure.trailing_speedup(r["push"])),
    Claim("push_to_cr", "T- pulses reach c_r at the far end", "Sec. 3.1.2: \"until they accelerate to c_r at the "
          "right end of the contact\"", "~1", "c_r", between(0.7, 1.2, why="the paper's own 0.7-1 c_r lattice "
          "scatter (Sec. 3.3.2), and no faster than c_s/c_r = 1.10 by more than the scatter"), PUSH_RUN,
          lambda r: measure.max_speed_near_far_edge(r["push"])),
    Claim("push_pulse", "T- fronts are pulses (bonds re-attach behind the tip)", "Sec. 3.1: \"bond reformation "
          "occurs at the trailing end so that the rupture has a finite width\"", "all pulses", "share",
          at_least(1.0, why=_ALL), PUSH_RUN, lambda r: measure.pulse_share(r["push"])),
    Claim("push_in_flight", "T- three pulses in flight when the fourth nucleates (t = 35.1)", "Sec. 3.1.3: "
          "\"the interaction of three pulses ... for time tc_r/l = 35.1; another new pulse is about to "
          "simultaneously nucleate\"", "3", "pulses", between(3, 3, why="a count"), PUSH_RUN,
          lambda r: measure.in_flight_at_nucleation(r["push"], 3)),
    Claim("push_width", "T- pulse width about one spacing", "App. A: \"the pulse width remains almost constant "
          "within a one-unit spacing (i.e., w/l = 0.01)\"", "~1", "a", at_most(2.0, why="one spacing more than "
          "the paper's one: widths are whole sites"), PUSH_RUN, lambda r: measure.steady_width(r["push"])),
    Claim("push_width_constant", "T- pulse width constant during propagation", "Sec. 3.1.1: \"the pulses all have "
          "constant width\"; App. A: \"almost constant within a one-unit spacing\"", "within 1 a", "a (p90 - p10)",
          at_most(1.0, why="the paper's one unit"), PUSH_RUN, lambda r: measure.width_variation(r["push"])),
    Claim("push_width_far", "T- pulses widen near the far edge", "App. A: \"As the pulse nears the opposite "
          "boundary, its width tends to expand\"", "wider", "a (far - steady)", at_least(1.0, why="one whole site"),
          PUSH_RUN, lambda r: measure.far_edge_widening(r["push"])),
    Claim("push_width_jump", "T- trailing pulse widens when the leading one accelerates", "App. A: \"This "
          "acceleration causes a subsequent increase in the trailing pulses' widths\" (instances a, b, c)",
          "jump", "a", at_least(1.0, why="one whole site"), PUSH_RUN, lambda r: measure.width_jump(r["push"])),
    Claim("push_v0", "T- pulse speed proportional to v0 (v0/c_r = 1e-2, 1e-3, 1e-4)", "Sec. 3.1.2: \"the first, "
          "second and third pulses in each case travel with a speed v ∝ v0\"", "v/v0 curves coincide",
          "max/min of v/v0", at_most(1.2, why="20 %: curves 'nearly on top of each other'"),
          ("push_v0_1e-2", "push", "push_v0_1e-4"),
          lambda r: measure.v_over_v0_spread([r["push_v0_1e-2"], r["push"], r["push_v0_1e-4"]])),
    Claim("push_sxy_edge", "T- shear stress maximum at the rear edge before the first break", "Sec. 3.1.3: "
          "\"the developed stress field clearly exhibits a local maximum at the left (rear) edge x/l=0\"", "0", "l",
          at_most(0.05, why=_EDGE), PUSH_RUN, lambda r: measure.argmax_before_break(r["push"], "sxy")),
    Claim("push_tip_peak", "T- stress peak at the tip constant during propagation", "Sec. 3.1.3: \"the stress "
          "peak ... at the tip of the pulse remains constant during propagation\"", "constant",
          "max/min of the sxy peak", at_most(1.25, why="25 %: read off curves in Fig. 3b"), PUSH_RUN,
          lambda r: measure.tip_peak_constancy(r["push"])),
    Claim("push_mode2_first", "T- square-root singular shear stress ahead of the first pulse (K_II fit)",
          "App. B: \"conforms to the asymptotic square-root singular solution\"", "fits", "R^2 of the fit",
          at_least(0.9, why="a straight line of sigma^-2 on xi that explains 90 % of its variance"), PUSH_RUN,
          lambda r: measure.mode2_first_pulse(r["push"])),
    Claim("push_mode2_later", "T- square-root fits of the second and third pulses", "App. B: \"a square-root "
          "fitting is demonstrated for the second pulse ... and the third pulse\"", "fits", "R^2 of the fit",
          at_least(0.9, why="as for the first pulse"), PUSH_RUN, lambda r: measure.mode2_later_pulses(r["push"])),
    Claim("push_sxx", "T- block in compression (sigma_xx < 0) at t = 30", "Sec. 3.2.5: \"For T-, the observed v "
          "is positive, so that epsilon_xx is compressive\"", "< 0", "rho c_r^2", at_most(0.0, why="a sign"), PUSH_RUN,
          lambda r: measure.mean_block_sxx(r["push"], 30.0)),
    # --- T+ (pull), Sec. 3.2 ---------------------------------------------------------------
    Claim("pull_first", "T+ first nucleation", "Fig. 5 caption: \"5.4 (blue)\"", "5.4", "l/c_r",
          near(5.4, rel=0.03, why=_TIME3), PULL_RUN, lambda r: measure.nucleation_time(r["pull"], 0)),
    Claim("pull_next", "T+ second to fourth nucleations", "Fig. 5 caption: \"15.5 (orange), 25.7 (green), and "
          "35.7 (brown)\"", "15.5, 25.7, 35.7", "l/c_r", near((15.5, 25.7, 35.7), abs=1.0, why=_TIME1), PULL_RUN,
          lambda r: measure.nucleation_times(r["pull"])[1:4]),
    Claim("pull_site", "T+ pulses nucleate at the front edge", "Sec. 3.2: \"they now nucleate at the leading "
          "face\"", "1", "l (distance from 1)", at_most(0.05, why=_EDGE), PULL_RUN,
          lambda r: 1.0 - measure.nucleation_site(r["pull"])),
    Claim("pull_direction", "T+ pulses run toward x/l = 0", "Sec. 3.2: \"propagate towards the rear, or in a "
          "direction opposite to the imposed motion\"", "all toward 0", "share", at_least(1.0, why=_ALL), PULL_RUN,
          lambda r: measure.directions(r["pull"])),
    Claim("pull_interval", "T+ pulse interval", "Fig. 5 caption: 5.4, 15.5, 25.7, 35.7", "10.1", "l/c_r",
          near(10.1, rel=0.05, why="as for T-"), PULL_RUN, lambda r: measure.interval(r["pull"])),
    Claim("pull_slow", "T+ pulses far slower than c_r", "Sec. 3.2.1: \"The speeds are far lower than the "
          "corresponding Rayleigh wave speed\"", "<< 1", "c_r", at_most(0.1, why=_SLOW), PULL_RUN,
          lambda r: measure.mean_steady_speed(r["pull"])),
    Claim("pull_accel_x", "T+ leading pulse accelerates near x/l = 0", "Sec. 3.2.1: \"these pulses accelerate "
          "when the approach the other end, here x/l=0\" (mirror of T-'s 0.7-0.8)", "0.2-0.3", "l",
          between(0.15, 0.35, why="the mirror of T-'s 0.65-0.85"), PULL_RUN, lambda r: measure.accel_x(r["pull"])),
    Claim("pull_accel_time", "T+ leading pulse meets the rear edge at t = 55", "Sec. 3.2.3: \"At tc_r/l = 55, the "
          "stress field of the leading pulse begins to interact with the rear edge\"", "55", "l/c_r",
          near(55.0, abs=5.0, why="5 l/c_r: half a pulse interval"), PULL_RUN, lambda r: measure.leading_accel_time(r["pull"])),
    Claim("pull_pulse", "T+ fronts are pulses", "Sec. 3.2: \"Similar pulses are observed\"", "all pulses", "share",
          at_least(1.0, why=_ALL), PULL_RUN, lambda r: measure.pulse_share(r["pull"])),
    Claim("pull_in_flight", "T+ three pulses in flight when the fourth nucleates (t = 35.7)", "Sec. 3.2.3: "
          "\"their tips are marked individually for tc_r/l = 35.7 when the fourth pulse is about to "
          "nucleate\"", "3", "pulses", between(3, 3, why="a count"), PULL_RUN,
          lambda r: measure.in_flight_at_nucleation(r["pull"], 3)),
    Claim("pull_secondary", "T+ secondary fronts from x/l ~ 0.1 toward the pulses", "Sec. 3.2.2: \"ocassional "
          "secondary fronts that appear to originate from the trailing edge x/l ~ 0.1\"", ">= 1", "fronts",
          at_least(1, why="'occasional': at least one in 100 l/c_r, born 0.03-0.25 l from the rear edge"), PULL_RUN,
          lambda r: measure.secondary_fronts(r["pull"])),
    Claim("pull_sxx", "T+ block in tension (sigma_xx > 0) at t = 30", "Sec. 3.2.5: \"The converse holds for T+, "
          "the longitudinal strain component is tensile\"", "> 0", "rho c_r^2", at_least(0.0, why="a sign"), PULL_RUN,
          lambda r: measure.mean_block_sxx(r["pull"], 30.0)),
    Claim("pull_push_speed", "T+ pulses 50 % slower than T-", "App. D: \"the pulses are 50% slower in pulling as "
          "compared to pushing\"", "0.5", "v(T+)/v(T-)", near(0.5, abs=0.1, why="0.1: the paper's round 50 %"),
          ("push", "pull"), lambda r: measure.speed_ratio(r["pull"], r["push"])),
    Claim("pull_compressive", "T+ more compressive sigma_yy at nucleation than T-", "App. D: \"the more "
          "prominently compressive nature of sigma_yy at nucleation in pulling compared to pushing\"", "T+ < T-",
          "min syy T+ - T- (rho c_r^2)", at_most(0.0, why="a sign"), ("push", "pull"),
          lambda r: measure.min_before_break(r["pull"]) - measure.min_before_break(r["push"])),
    # --- T0 (shear), Sec. 3.3 --------------------------------------------------------------
    Claim("shear_first", "T0 first break", "Sec. 3.3.3: \"the first breaking event occurs much later, at "
          "tc_r/l = 65.37\"", "65.37", "l/c_r", near(65.37, rel=0.02, why="2 %: the project's target for T0"), SHEAR_RUN,
          lambda r: first_break_time(r["shear"])),
    Claim("shear_site", "T0 rupture nucleates at the rear edge", "Sec. 3.3: \"Rupture fronts nucleate at the left "
          "edge of the body\"", "0", "l", at_most(0.05, why=_EDGE), SHEAR_RUN, lambda r: measure.nucleation_site(r["shear"])),
    Claim("shear_crossing", "T0 first front crosses the contact by t = 66.50", "Sec. 3.3.3: \"these fast fronts "
          "rupture the entire interface ..., see the sigma_xy field at tc_r/l = 66.50\" (65.37 -> 66.50)", "1.13",
          "l/c_r", at_most(1.5, why="crossing at 0.7 c_r, the slow end of the paper's 0.7-1 c_r"), SHEAR_RUN,
          lambda r: crossing_time(r["shear"], 0)),
    Claim("shear_speed", "T0 first front at ~c_r past x_tip/l ~ 0.2", "Sec. 3.3.2: \"the fronts quickly "
          "accelerate to v ~ c_r ... fluctuation between 0.7c_r and c_r ... an artifact\"", "0.7-1", "c_r",
          between(0.7, 1.05, why="the paper's band, 5 % headroom for the frame cadence"), SHEAR_RUN,
          lambda r: crack_speed(r["shear"], 0)),
    Claim("shear_later_speed", "T0 later fronts reach c_r quickly too", "Sec. 3.3.2: \"All temporally sequential "
          "fronts reach the Rayleigh wave speed quickly, even as x_tip/l ~ 0.2\"", "0.7-1", "c_r (slower of "
          "fronts 2, 3)", between(0.7, 1.05, why="as for the first front"), SHEAR_RUN,
          lambda r: measure.later_crack_speeds(r["shear"])),
    Claim("shear_subshear", "T0 no supershear front", "Sec. 3.3.2: \"fronts cannot propagate at speeds faster "
          "than this---we do not observe any super-shear ruptures\"", "<= c_s = 1.10 c_r", "c_r",
          at_most(1.1, why="c_s/c_r = 1.098 at nu = 0.2"), SHEAR_RUN, lambda r: peak_speed(r["shear"], 0)),
    Claim("shear_crack", "T0 re-attachment only after the front crossed (crack)", "Sec. 3.3.1: \"this process "
          "starts after the rupture has propagated the entire length of the interface\"", ">= 0",
          "l/c_r (first re-bond - crossing)", at_least(0.0, why="the order of two events"), SHEAR_RUN,
          lambda r: measure.rebond_after_crossing(r["shear"], 0)),
    Claim("shear_uneven", "T0 re-bonding uneven, some regions detached much longer", "Sec. 3.3.1: \"Reattachment "
          "is also non-homogeneous, with some regions remaining unbonded for a finite amount of time\"",
          "uneven", "longest / median detachment", at_least(2.0, why="a region open at least twice as long as "
          "the typical site"), SHEAR_RUN, lambda r: measure.rebond_unevenness(r["shear"], 0)),
    Claim("shear_sxy_centre", "T0 shear stress rises from the edges to the centre before rupture",
          "Sec. 3.3.3: \"uneven shear stress at the contact interface, increasing from the edges to the central "
          "part\"", "> 1", "centre / edges", at_least(1.1, why="10 %: a rise the eye sees in Fig. 7b"), SHEAR_RUN,
          lambda r: measure.centre_over_edges(r["shear"], "sxy")),
    Claim("shear_syy_edge", "T0 normal stress largest (tensile) at the nucleation edge", "Sec. 3.3.3: \"the "
          "additional contribution at the nucleation site (edge) comes from the normal stress having a positive "
          "maximum value\"", "0", "l", at_most(0.05, why=_EDGE), SHEAR_RUN, lambda r: measure.argmax_before_break(r["shear"], "syy")),
    Claim("shear_tip_peaks", "T0 peaks of both sigma_xy and sigma_yy travel with the tip", "Sec. 3.3.3: \"we "
          "observe stress peaks in both normal and shear components during rupture propagation\"", "both",
          "share of the two", at_least(1.0, why="both components"), SHEAR_RUN,
          lambda r: measure.tip_carries_both_peaks(r["shear"])),
    Claim("shear_same_slip", "T0 all locations slip alike", "Sec. 3.4: \"we see all three locations appear to "
          "slip in the same manner with time\"", "alike", "max/min at x/l = 0, 0.35, 0.98",
          at_most(1.5, why="50 %: 'in the same manner', read off Fig. 10b"), SHEAR_RUN,
          lambda r: measure.same_slip_everywhere(r["shear"])),
    Claim("shear_sharp", "T0 sharp slip-velocity peak at x/l = 0, 0.35, 0.98", "App. C: \"the developed "
          "crack-like front being fast induces a sharp peak in slip velocity at all three locations\"", "sharp",
          "peak / median |u-dot|", at_least(20.0, why="a peak an order of magnitude and more above the creep"), SHEAR_RUN,
          lambda r: measure.sharp_peaks(r["shear"])),
    # --- slip, Sec. 3.4 and App. C ---------------------------------------------------------------
    Claim("push_slip", "T- slip per pulse", "Sec. 3.4: \"each pulse or rupture front causes constant unit slip "
          "varying from ~0.04 l to 0.011l\"", "0.011-0.04", "l", between(0.0088, 0.048, why="the paper's range, "
          "20 % wider at each end for its '~'"), PUSH_RUN, lambda r: measure.median_front_slip(r["push"], 6)),
    Claim("push_slip_constant", "T- each pulse carries the same slip", "Sec. 3.4: \"each pulse is responsible "
          "for constant slip\"", "constant", "std/mean, pulses 2-6", at_most(0.1, why="10 %: markers 'on "
          "horizontal lines'"), PUSH_RUN, lambda r: measure.slip_spread(r["push"])),
    Claim("push_first_slip", "T- first pulse slips more than the next", "Sec. 3.4: \"Delta u for the first "
          "front, in both T-, T0 cases is generally larger than with subsequent pulses\"", "> 1",
          "first / median of 2-3", at_least(1.05, why="5 %: larger beyond the spread of pulses 2-3"), PUSH_RUN,
          lambda r: measure.first_front_excess(r["push"])),
    Claim("shear_first_slip", "T0 first front slips more than the next", "Sec. 3.4: \"Delta u for the first "
          "front, in both T-, T0 cases is generally larger\"", "> 1", "first / median of 2-3",
          at_least(1.05, why="as for T-"), SHEAR_RUN, lambda r: measure.first_front_excess(r["shear"])),
    Claim("slip_ratio", "slip per front, T- over T0", "Sec. 3.4: \"Local slip is almost 25% larger in the pulse "
          "(T-) case compared to the crack (T0) case\"", "1.25", "ratio", near(1.25, abs=0.1, why="0.1: 'almost "
          "25 %' read as 15-35 %"), ("push", "shear"),
          lambda r: measure.median_front_slip(r["push"], 6) / measure.median_front_slip(r["shear"], 3)),
    Claim("push_stationary", "T- interface does not slip between pulses", "Sec. 3.4: \"between successive "
          "pulses, the interface remains stationary and there is no slip\"", "all slip in passages",
          "share of u at x/l = 0.5", at_least(0.8, why="80 %: the drive's creep v0 t between pulses is allowed"),
          PUSH_RUN, lambda r: slip.slip_share_in_passages(r["push"], 0.5)),
    Claim("push_no_net_v", "T- no net vertical displacement after a pulse", "Sec. 3.4: \"there is no net slip in "
          "the y direction and the bodies readhere\"", "0", "|Delta v| / Delta u", at_most(0.1, why="10 % of "
          "the slip"), PUSH_RUN, lambda r: measure.net_vertical_over_slip(r["push"])),
    Claim("push_lift", "T- interface lifts (Delta v > 0) at the nucleation edge", "Sec. 3.4: \"Delta v > 0 at "
          "the left edge of the contact (x/l = 0) where nucleation occurs\"", "> 0", "l",
          at_least(0.0, why="a sign"), PUSH_RUN, lambda r: measure.lift_at_nucleation(r["push"])),
    Claim("push_udot_mid", "T- slip velocity at x/l = 0.35 rises with each pulse and falls after",
          "App. C: \"At any midpoint (say x/l=0.35), u-dot increases upon the pulse's arrival and decreases upon "
          "its departure\"", "rises", "mean u-dot in passages / outside", at_least(3.0, why="a clear contrast"),
          PUSH_RUN, lambda r: measure.passage_contrast(r["push"], 0.35)),
    Claim("push_udot_far", "T- x/l = 0.98 stays put until the first pulse arrives", "App. C: \"The point situated "
          "at the opposite edge (x/l=0.98) remains stationary until the advancing pulse ... induces a sudden "
          "jump\"", "0", "u before arrival / pulse slip", at_most(0.2, why="a fifth of one pulse's slip"), PUSH_RUN,
          lambda r: measure.stationary_before_arrival(r["push"], 0.98)),
    Claim("crack_faster_slip", "T0 slip velocity peaks above T-'s", "Sec. 3.4: \"pulses having a lower and more "
          "gradual slip velocity than crack-like fronts with a sudden, sharp jump\"", "> 1",
          "peak u-dot T0 / T- at x/l = 0.35", at_least(2.0, why="a factor 2"), ("push", "shear"),
          lambda r: slip.peak_slip_velocity(r["shear"], 0.35) / slip.peak_slip_velocity(r["push"], 0.35)),
    # --- larger contacts, Sec. 4.4 -------------------------------------------------------------
    Claim("l300_push", "l = 300: T- still forward pulses from the rear edge", "Sec. 4.4: \"l=300 contacts point, "
          "retains similar qualitative behaviour for all loading conditions\"", "pulses from 0 toward 1",
          "share of edge fronts that are pulses running forward", at_least(1.0, why=_ALL), ("push_l300",),
          lambda r: _pulses_away(r["push_l300"])),
    Claim("l300_pull", "l = 300: T+ still backward pulses from the front edge", "Sec. 4.4: \"retains similar "
          "qualitative behaviour for all loading conditions\"", "pulses from 1 toward 0", "share",
          at_least(1.0, why=_ALL), ("pull_l300",), lambda r: _pulses_away(r["pull_l300"])),
    Claim("l300_shear", "l = 300: T0 still a fast rupture from the rear edge", "Sec. 4.4: \"retains similar "
          "qualitative behaviour for all loading conditions\"", "~c_r from x/l = 0", "c_r",
          between(0.7, 1.05, why="as at l = 100"), ("shear_l300",), lambda r: _fast_from_edge(r["shear_l300"])),
    Claim("l500_crack", "l = 500: T0 front rapidly breaks all interface bonds", "Sec. 4.4: \"for l = 500 contact "
          "points ... a front rapidly breaks all interface bonds\"", "1", "largest share broken at once",
          at_least(0.95, why="all but the odd site"), ("shear_l500",),
          lambda r: measure.broken_share_at_crossing(r["shear_l500"], 0)),
    Claim("l500_uneven", "l = 500: uneven re-bonding, some regions slow", "Sec. 4.4: \"The reformation process "
          "... occurs unevenly, with some regions of interface bonds taking considerable time to rebond\"",
          "uneven", "longest / median detachment", at_least(2.0, why="as at l = 100"), ("shear_l500",),
          lambda r: measure.rebond_unevenness(r["shear_l500"], 0)),
]


def _pulses_away(run) -> float:
    """Share of a run's edge fronts that are pulses running away from the driven edge (NaN without any)."""
    fr = measure.edge_fronts(run)
    if not fr:
        return math.nan
    away = -1 if run.mode == "pull" else 1
    return sum(f.kind == "pulse" and f.direction == away for f in fr) / len(fr)


def _fast_from_edge(run) -> float:
    """Median speed (c_r) past 0.2 l of the first front, if it nucleated at the driven edge; else 0."""
    fr = run.fronts()
    if not fr:
        return math.nan
    return crack_speed(run, 0) if abs(fr[0].nucleation_x - driven_edge(run)) < measure.EDGE else 0.0


def _passage_ratio(runs) -> float:
    push = [slip.passage_slip(runs["push"], i) for i in range(1, 6)]
    shear = [slip.passage_slip(runs["shear"], i) for i in range(0, 3)]
    push, shear = [v for v in push if math.isfinite(v)], [v for v in shear if math.isfinite(v)]
    if not push or not shear:
        return math.nan
    import numpy as np
    return float(np.median(push) / np.median(shear))


# Other ways to read a measurement off the same runs: the analysis-only causes a disagreement could have.
# claim key -> [(what the other reading is, measure on the runs)]
ALTERNATIVES: dict[str, list[tuple[str, Callable[[dict], object]]]] = {
    "push_width": [("white runs in the constant-time section t c_r/l = 30 (the paper's own reading, Sec. 3.1.1)",
                    lambda r: section_width(r["push"], 30.0))],
    "pull_push_speed": [("each pulse's mean speed over its whole run, acceleration included",
                         lambda r: measure.speed_ratio(r["pull"], r["push"], how="mean"))],
    "slip_ratio": [("the jump while a front passes (passage_slip), without the creep between fronts",
                    _passage_ratio)],
    "push_stationary": [("the share at x/l = 0.98, near the far edge (Fig. 10a: 'more pronounced')",
                         lambda r: slip.slip_share_in_passages(r["push"], 0.98))],
    "push_same_speed": [("the first three pulses only", lambda r: measure.speed_spread(r["push"], 3))],
}


def alternatives(runs: dict) -> list[dict]:
    """Each ``ALTERNATIVES`` measurement on ``runs``: rows of key, how, value (formatted), verdict against
    the claim's own tolerance."""
    by = {c.key: c for c in CLAIMS}
    out = []
    for key, alts in ALTERNATIVES.items():
        c = by[key]
        for how, fn in alts:
            if any(k not in runs for k in c.needs):
                continue
            try:
                v = fn(runs)
            except (IndexError, ValueError, ZeroDivisionError, KeyError):
                v = None
            out.append({"key": key, "how": how, "parslip": fmt(v), "verdict": verdict(c.accept, v)})
    return out


def evaluate(runs: dict, claims=None) -> list[dict]:
    """One row per claim: key, claim, source, paper, parslip (formatted), value (raw, JSON-ready), units,
    tolerance, verdict; 'not measured' when a run is missing or holds too little."""
    rows = []
    for c in claims or CLAIMS:
        missing = [k for k in c.needs if k not in runs]
        value, note = None, ""
        if missing:
            note = f"not run: {', '.join(missing)}"
        else:
            try:
                value = c.measure(runs)
            except (IndexError, ValueError, ZeroDivisionError, KeyError) as e:   # too few fronts, no snapshot
                note = f"{type(e).__name__}: {e}"[:120]
        v = verdict(c.accept, value)
        rows.append({"key": c.key, "claim": c.claim, "source": c.source, "paper": c.paper,
                     "parslip": note if v == NOT_MEASURED and note else fmt(value),
                     "value": _jsonable(value), "units": c.units, "tolerance": c.tolerance, "verdict": v})
    return rows


def _jsonable(v):
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if v is None or isinstance(v, (bool, str)):
        return v
    try:
        f = float(v)
    except (TypeError, ValueError):
        return str(v)
    return f if math.isfinite(f) else None


def share_agreeing(rows: list[dict]) -> float:
    """Agreeing rows over all rows: 'not measured' counts against."""
    return sum(r["verdict"] == AGREES for r in rows) / len(rows) if rows else math.nan


def counts(rows: list[dict]) -> dict:
    return {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}


def to_markdown(rows: list[dict], title: str = "") -> str:
    c = counts(rows)
    head = [f"# {title}", ""] if title else []
    head += [f"{c[AGREES]} of {len(rows)} claims agree ({share_agreeing(rows):.0%}); {c[DISAGREES]} disagree, "
             f"{c[NOT_MEASURED]} not measured.", "",
             "| # | claim | source | paper | parslip | units | tolerance | verdict |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for i, r in enumerate(rows, 1):
        cells = [str(i)] + [str(r[k]).replace("|", "\\|") for k in
                            ("claim", "source", "paper", "parslip", "units", "tolerance")]
        cells.append(f"**{r['verdict']}**" if r["verdict"] != AGREES else r["verdict"])
        head.append("| " + " | ".join(cells) + " |")
    return "\n".join(head) + "\n"


def to_json(rows: list[dict], **extra) -> str:
    keys = ("key", "claim", "source", "paper", "parslip", "value", "units", "tolerance", "verdict")
    return json.dumps({"share_agreeing": share_agreeing(rows), "counts": counts(rows), **extra,
                       "claims": [{k: r[k] for k in keys} for r in rows]}, indent=1, ensure_ascii=False)
