// java DecodeLog LOG: reads an LCM log and decodes every message the way lcm-spy does: the
// class is looked up by the type hash (the first 8 bytes of the message) in
// lcm.spy.LCMTypeDatabase, which discovers the classes of the jars on CLASSPATH. Prints one
// line per message: "msg <channel> <class>" then, for svslam_lcm.pose_t, " seq <n> utime <us>
// position <x> <y> <z>", or "msg <channel> unknown" when no class on CLASSPATH has the hash
// (LCMTypeDatabase's own progress lines do not start with "msg ").
// Exit 0 when the log was read to its end, 1 on an error.
import java.io.EOFException;
import java.lang.reflect.Field;
import java.util.Locale;
import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class DecodeLog {
  public static void main(String[] args) throws Exception {
    if (args.length != 1) {
      System.err.println("usage: java DecodeLog LOG");
      System.exit(2);
    }
    LCMTypeDatabase db = new LCMTypeDatabase();
    Log log = new Log(args[0], "r");
    while (true) {
      Log.Event ev;
      try {
        ev = log.readNext();
      } catch (EOFException end) {
        break;
      }
      long hash = 0;
      for (int i = 0; i < 8 && i < ev.data.length; ++i) hash = (hash << 8) | (ev.data[i] & 0xff);
      Class<?> cls = db.getClassByFingerprint(hash);
      if (cls == null) {
        System.out.println("msg " + ev.channel + " unknown");
        continue;
      }
      Object msg = cls.getConstructor(byte[].class).newInstance((Object) ev.data);
      StringBuilder line = new StringBuilder("msg " + ev.channel + " " + cls.getName());
      if (cls.getName().equals("svslam_lcm.pose_t")) {
        double[] p = (double[]) field(cls, "position").get(msg);
        line.append(" seq ").append(field(cls, "seq").getLong(msg));
        line.append(" utime ").append(field(cls, "utime").getLong(msg));
        line.append(String.format(Locale.ROOT, " position %.6f %.6f %.6f", p[0], p[1], p[2]));
      }
      System.out.println(line);
    }
    log.close();
  }

  static Field field(Class<?> cls, String name) throws NoSuchFieldException {
    return cls.getField(name);
  }
}
