"""The manipulation domains (Shelf, OpenDrawer, OpenDoor): the one package that joins
the world, the skills, perception and the planners.

- :mod:`.tasks`: the tasks (``ShelfTask``, ``OpenDrawerTask``, ``OpenDoorTask``,
  registered as ``shelf``, ``opendrawer``, ``opendoor``), each the twins' POMDP and
  the real robot as its environment;
- :mod:`.model`: the twins' POMDP (step, applicable, likelihoods; no belief and no
  real world);
- :mod:`.real`: the real Fetch and cabinet as an environment (the real step, the
  model it plans in, the refusals, the head camera's cloud);
- :mod:`.episode_setup`: the real cabinet of an episode and its target;
- :mod:`.catalogue`: the episode's catalogued parts and the search's root values;
- :mod:`.grounding`: an action's skills and planning world, its handle, its reward;
- :mod:`.conditioning`: the real belief given what the robot knows for certain;
- :mod:`.state`: states and observations;
- :mod:`.actions`: the skills as actions, parts named by where they are;
- :mod:`.worlds`: the particles' compiled worlds and the caches;
- :mod:`.rules`: what the tasks count as success and failure;
- :mod:`.belief`: the initial belief from perception.
"""
