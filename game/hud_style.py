"""The HUD's colours and layout constants, shared by the HUD, the two-player HUD and the F3
overlay (game/hud.py, game/hud_two_player.py, game/hud_budget.py)."""

PLAYER_COLOR = (235, 64, 52)
OPPONENT_COLOR = (52, 120, 235)
BAR_BACK = (34, 30, 38)
BAR_LOSS = (250, 210, 90)  # the recently lost health, shown draining after the fill
TEXT = (242, 240, 232)
DIM = (170, 166, 160)
KEY_TEXT = (228, 225, 218)  # the key legend, on its dark panel
SWITCH_COLOR = (255, 200, 40)
REJECT_COLOR = (255, 70, 70)
OK_COLOR = (90, 220, 120)
STAGE_COLORS = [
    (102, 194, 165), (252, 141, 98), (141, 160, 203), (231, 138, 195), (166, 216, 84),
    (255, 217, 47), (229, 196, 148), (179, 179, 179), (120, 200, 240), (240, 120, 120),
]
MARK_STEPS = 45  # how long a switch / reject mark stays lit
# A plain reject this soon after a motion's `end` is that motion's return (the virtual player's
# demo: 63 such rejects in 2 minutes, 6-19 steps after the end, against 113 recognized moves): the
# HUD keeps the recognized move up and lights no REJECT mark, which had flashed after most punches.
TAIL_STEPS = 30
CHART_BG = (30, 30, 36)
TEXT_EVERY = 10  # frames between refreshes of the F3 overlay's numbers
COUNT_X = 0.3  # the knockdown count's centre, as a fraction of the width
BUDGET_HEADERS = ("stage", "last ms", "p99 / budget ms", "overruns")
BUDGET_COLUMNS = (0, 110, 185, 320)  # their x in the F3 panel (720p pixels from the colour key)
HISTORY_FRAMES = 120  # the F3 overlay's chart: the last two seconds, a stacked column a frame

# The smallest text drawn (pygame's default font at 16 px: caps 8 px, line 12 px), the size of the
# smallest text at 1280x720 (the F3 table's headers, the training plot's legend). The HUD's type
# scales with the window's height, u = height / 720; below 720 p text stops shrinking here (at
# 800x450, u = 0.625, the 18 px labels were 11 px: caps 5 px). Pixels on a 7-inch 800x480 screen
# at arm's length subtend about what a television's do from the sofa, so what reads at 720 p
# reads there at the same pixel size.
MIN_TEXT_PX = 16
TEXT_SCALE_FLOOR = MIN_TEXT_PX / 18  # the panels holding 18 px (720 p) labels scale no further down
# ... on windows down to 800x450 (u = 0.625, the smallest screen played on). A smaller window (a
# 640x360 window, a thumbnail) is a picture of the game, not a screen to read at arm's length: the
# floor shrinks with it, so two players' key legends still fit side by side.
FLOOR_DOWN_TO_U = 0.625


def min_text_px(u: float) -> int:
    """The smallest text drawn in a window of scale u (= height / 720): MIN_TEXT_PX down to
    FLOOR_DOWN_TO_U, then shrinking with the window."""
    return max(1, int(MIN_TEXT_PX * min(1.0, u / FLOOR_DOWN_TO_U)))


def text_scale(u: float) -> float:
    """The scale of the panels and lines that hold small text: the window's u, down to the point
    where their 18 px labels reach the floor (so a panel grows around text that stops shrinking)."""
    return max(u, TEXT_SCALE_FLOOR * min(1.0, u / FLOOR_DOWN_TO_U))
