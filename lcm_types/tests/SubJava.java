// SubJava - a Java decoder of the daemon's poses through the generated jar (rigpose_lcm.jar)
// and Debian's lcm.jar.  usage: java -cp lcm.jar:rigpose_lcm.jar:DIR SubJava URL CHANNEL EXPECT READY
// Subscribes, creates READY, receives until EXPECT poses arrived (60 s at most), checks seq
// 0..EXPECT-1 in order and the quaternion's norm; prints "SubJava: ok" or "SubJava: FAIL".
import java.io.File;
import java.io.IOException;

import lcm.lcm.LCM;
import lcm.lcm.LCMDataInputStream;
import lcm.lcm.LCMSubscriber;
import rigpose.pose_t;

public class SubJava implements LCMSubscriber {
    private int n = 0;
    private int bad = 0;

    @Override
    public synchronized void messageReceived(LCM lc, String channel, LCMDataInputStream in) {
        try {
            pose_t m = new pose_t(in);
            double q = 0;
            for (double x : m.quaternion) q += x * x;
            if (m.seq != n || Math.abs(Math.sqrt(q) - 1) > 1e-9) {
                if (bad++ < 5) System.out.println("pose " + n + ": seq " + m.seq + " |q|^2 " + q);
            }
        } catch (IOException e) {
            if (bad++ < 5) System.out.println("pose " + n + ": cannot decode: " + e);
        }
        n++;
        notifyAll();
    }

    public static void main(String[] args) throws Exception {
        if (args.length != 4) {
            System.err.println("usage: SubJava URL CHANNEL EXPECT READYFILE");
            System.exit(2);
        }
        int expect = Integer.parseInt(args[2]);
        LCM lc = new LCM(args[0]);
        SubJava s = new SubJava();
        lc.subscribe(args[1], s);
        if (!new File(args[3]).createNewFile()) System.out.println("ready file existed");
        long end = System.currentTimeMillis() + 60000;
        synchronized (s) {
            while (s.n < expect && System.currentTimeMillis() < end) s.wait(100);
        }
        Thread.sleep(300);
        synchronized (s) {
            System.out.println("Java decoder (rigpose.pose_t): " + s.n + " poses (expected "
                    + expect + "), " + s.bad + " problems");
            boolean ok = s.n == expect && s.bad == 0;
            System.out.println(ok ? "SubJava: ok" : "SubJava: FAIL");
            lc.close();
            System.exit(ok ? 0 : 1);
        }
    }
}
