"""The manipulation domains (Shelf, OpenDrawer, OpenDoor): the one package that joins
the world, the skills, perception and the planners.

- :mod:`.model`: the POMDPs (``ShelfTask``, ``OpenDrawerTask``, ``OpenDoorTask``,
  registered as ``shelf``, ``opendrawer``, ``opendoor``);
- :mod:`.state`: states and observations;
- :mod:`.actions`: the skills as actions, parts named by where they are;
- :mod:`.worlds`: the particles' compiled worlds and the caches;
- :mod:`.rules`: what the tasks count as success and failure;
- :mod:`.belief`: the initial belief from perception.
"""
