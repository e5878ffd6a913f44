/* Loads a scene in Debian's MuJoCo 2.2.2, places part B at (ox, oy), presses part A at
   the nominal goal from height z0 with force f and prints the raw force/torque sensor. */
#include <stdio.h>
#include <stdlib.h>
#include <mujoco/mujoco.h>

int main(int argc, char **argv) {
  if (argc != 6) { fprintf(stderr, "usage: %s scene.xml ox oy z0 force\n", argv[0]); return 2; }
  char err[1000] = "";
  mjModel *m = mj_loadXML(argv[1], NULL, err, sizeof err);
  if (!m) { fprintf(stderr, "load: %s\n", err); return 1; }
  mjData *d = mj_makeData(m);
  d->mocap_pos[0] = atof(argv[2]);
  d->mocap_pos[1] = atof(argv[3]);
  d->qpos[2] = atof(argv[4]);
  d->ctrl[2] = -atof(argv[5]);
  for (int i = 0; i < 600; i++) mj_step(m, d);
  printf("version %d\n", mj_version());
  for (int i = 0; i < 6; i++) printf("%.9g ", d->sensordata[i]);
  printf("\n%.9g\n", d->qpos[2]);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
