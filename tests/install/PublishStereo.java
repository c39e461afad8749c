// java PublishStereo URL CHANNEL FRAMES RATE_HZ: a stand-in camera for trying svslam's LCM
// tools (docs/lcm.md) with svslam_lcm_types.jar: publishes FRAMES rectified stereo pairs
// (svslam_lcm.stereo_image_t, 320 x 240, random texture, the right image shifted by 8 px =
// disparity 8 px, f = 300 px, baseline 0.1 m, a static camera) at RATE_HZ on CHANNEL.
import java.util.Random;
import lcm.lcm.LCM;
import svslam_lcm.stereo_image_t;

public class PublishStereo {
  public static void main(String[] args) throws Exception {
    if (args.length != 4) {
      System.err.println("usage: java PublishStereo URL CHANNEL FRAMES RATE_HZ");
      System.exit(2);
    }
    LCM lcm = new LCM(args[0]);
    final int frames = Integer.parseInt(args[2]);
    final double rate_hz = Double.parseDouble(args[3]);
    final int w = 320, h = 240, disparity_px = 8;
    byte[] texture = new byte[w * h];
    new Random(1).nextBytes(texture);
    for (int i = 0; i < frames; ++i) {
      stereo_image_t m = new stereo_image_t();
      m.utime = System.currentTimeMillis() * 1000;
      m.seq = i;
      m.width = w;
      m.height = h;
      m.stride = w;
      m.f_px = 300.0;
      m.cx_px = w / 2.0;
      m.cy_px = h / 2.0;
      m.baseline_m = 0.1;
      m.left_size = w * h;
      m.right_size = w * h;
      m.left = texture.clone();
      m.right = new byte[w * h];
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          m.right[y * w + x] = texture[y * w + Math.min(w - 1, x + disparity_px)];
      lcm.publish(args[1], m);
      Thread.sleep((long) (1000.0 / rate_hz));
    }
    lcm.close();
  }
}
