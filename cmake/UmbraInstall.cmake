# Installation is added once the io library exists.
