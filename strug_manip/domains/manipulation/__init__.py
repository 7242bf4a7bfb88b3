"""The manipulation domains (Shelf, OpenDrawer, OpenDoor): what the tasks count as
success and failure from a skill's facts (:mod:`strug_manip.domains.manipulation.rules`)
and the initial belief from perception (:mod:`strug_manip.domains.manipulation.belief`);
the POMDPs themselves are still to come."""
