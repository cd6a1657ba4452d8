"""Matches of the virtual player against the CPU at each difficulty, through the real game:
`quickjab graph duel --opponent virtual`.

Each match is the real Session (recognizer, physics, Interaction Graph opponent with the
difficulty's policy, match rules; no rendering, no sound) on a virtual clock. The player's boxer
is driven by the attract-mode pilot through `keyboard://?profile=experienced|novice`: the
virtual player performs each move as Wiimote + Nunchuk readings and the REAL recognizer decides
what the boxer does, as it would for a person. A round is won on the round's points (damage,
knockdowns) or by ending the match in it (KO, TKO); rounds scored even count as draws.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

PROFILES = ("experienced", "novice")
MAX_STEPS = 3 * (60 + 3) * 60 + 60 * 60  # three rounds, two breaks, the counts


@dataclass
class MatchResult:
    difficulty: str
    profile: str
    seed: int
    round_winners: list[int | None]  # 0 the player, 1 the CPU, None even
    result: str  # KO, TKO, points, draw
    winner: int | None
    steps: int


def play_match(difficulty: str, profile: str, seed: int, graph: str | None = None,
               templates: str | None = None, max_steps: int = MAX_STEPS) -> MatchResult:
    """One whole match, headless (seconds of CPU per round)."""
    from tools.scripted_match import default_templates, headless_env

    headless_env()
    import pygame

    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from game.session import Session, SessionConfig

    pygame.init()
    clock = VirtualClock()
    source = open_source(f"keyboard://?profile={profile}&seed={seed}", clock=clock.seconds)
    cfg = SessionConfig(seed=seed, demo=True, sound=False, render=False, difficulty=difficulty, graph=graph,
                        templates=templates if templates is not None else default_templates())
    session = Session(source, cfg, clock=clock)
    try:
        session.loop.run(steps=max_steps, until=lambda: session.match.over)
    finally:
        source.close()
    m = session.match
    return MatchResult(difficulty, profile, seed, list(m.round_winners), m.result or "unfinished", m.winner,
                       session.loop.step_index)


@dataclass
class DuelSummary:
    difficulty: str
    profile: str
    matches: int = 0
    rounds: int = 0
    rounds_won: int = 0
    rounds_lost: int = 0
    matches_won: int = 0
    results: dict[str, int] = field(default_factory=dict)

    @property
    def round_win_rate(self) -> float:
        return self.rounds_won / max(self.rounds, 1)

    @property
    def rounds_per_match(self) -> float:
        return self.rounds / max(self.matches, 1)

    def add(self, r: MatchResult) -> None:
        self.matches += 1
        self.rounds += len(r.round_winners)
        self.rounds_won += sum(1 for w in r.round_winners if w == 0)
        self.rounds_lost += sum(1 for w in r.round_winners if w == 1)
        self.matches_won += int(r.winner == 0)
        self.results[r.result] = self.results.get(r.result, 0) + 1

    def as_dict(self) -> dict:
        return {"difficulty": self.difficulty, "player": self.profile, "matches": self.matches,
                "rounds": self.rounds, "rounds_won": self.rounds_won, "rounds_lost": self.rounds_lost,
                "round_win_rate": round(self.round_win_rate, 4), "rounds_per_match": round(self.rounds_per_match, 2),
                "matches_won": self.matches_won, "results": dict(sorted(self.results.items()))}


def _play(job: tuple) -> MatchResult:
    return play_match(*job)


def duel_jobs(difficulties: list[str], profiles: list[str], matches: int, seed: int,
              graph: str | None = None, templates: str | None = None) -> list[tuple]:
    """The matches to play: (difficulty, profile, seed, graph, templates), seeds seed, seed+1,
    ... wrapped into the seeds a URL takes (0..SEED_MAX)."""
    from engine.arguments import SEED_MAX

    return [(d, p, (seed + k) % (SEED_MAX + 1), graph, templates)
            for d in difficulties for p in profiles for k in range(matches)]


def virtual_duel(difficulties: list[str], profiles: list[str], matches: int, seed: int = 1, jobs: int = 2,
                 graph: str | None = None, templates: str | None = None) -> list[DuelSummary]:
    """`matches` matches per (difficulty, profile), seeds seed, seed+1, ...; `jobs` processes."""
    work = duel_jobs(difficulties, profiles, matches, seed, graph, templates)
    results = _in_processes(work, jobs) if jobs > 1 and len(work) > 1 else [_play(w) for w in work]
    summaries = {(d, p): DuelSummary(d, p) for d in difficulties for p in profiles}
    for r in results:
        summaries[(r.difficulty, r.profile)].add(r)
    return list(summaries.values())


def _in_processes(work: list[tuple], jobs: int) -> list[MatchResult]:
    """The matches played in `jobs` worker processes (engine.interrupt.as_worker: `kill` ends
    one, and each ends with this process). Interrupted (Ctrl-C, or SIGTERM / SIGHUP under
    stop_signals_as_ctrl_c), the workers are ended rather than waited for: the executor's
    shutdown waited for the matches under way, and a parent gone left them waiting for work."""
    from engine.interrupt import as_worker

    pool = ProcessPoolExecutor(max_workers=jobs, initializer=as_worker)
    try:
        # not pool.map, and nothing cancelled: a future map's cleanup cancelled was then failed by
        # the executor's thread as the workers ended (Python 3.11: an InvalidStateError traceback)
        futures = [pool.submit(_play, w) for w in work]
        return [f.result() for f in futures]
    except BaseException:
        _end_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True)


def _end_workers(pool: ProcessPoolExecutor) -> None:
    """SIGTERM to the pool's workers (terminate_workers() from Python 3.14; its processes before)."""
    end = getattr(pool, "terminate_workers", None)
    if end is not None:
        end()
        return
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        if process.exitcode is None:
            process.terminate()
