"""Pedestrians for any generated world: the social force model (Helbing & Molnár 1995, with
the group forces of Moussaïd et al. 2010) stepping a crowd of mocap bodies that the engine
moves, the ray casts see and the robot collides with. ``params`` is the ``crowd.*`` section
(no MuJoCo, read by the sim's parameters), ``forces`` the model's equations, ``obstacles``
the nearest points of the walls, ``crowd`` the crowd's state, goals and routes. ``movers``
moves a world's obstacles on smooth random trajectories (``dynbarn``), with the same
machinery: mocap bodies that the ray casts see and the robot touches."""
