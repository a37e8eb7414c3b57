namespace pdsm {}  // being written
