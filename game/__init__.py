"""The boxing game: actions and motion graph, controllers, the Interaction Graph at run time,
match rules, rendering, and the `quickjab` command."""
