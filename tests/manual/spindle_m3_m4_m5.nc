; TF5200 programming manual, "Spindle movement (M3/M4/M5)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/208029963.html
N10         S1000     (Speed 1000 rpm is stored, none)  (Spindle rotation because M05 is default)
N20  M03               (Spindle rotation cw at 1000 rpm)
N30  M04            (Spindle rotation ccw at 1000 rpm)
N40   S500      (Spindle rotation ccw at 500 rpm)
N50 M05  S300     (Spindle stop, speed 300 rpm is)  (stored)
N60  M04            (Spindle rotation ccw at 300 rpm)
N70  M05            (Spindle stop)
N80  M03   S1000   (Spindle rotation cw at 1000 rpm)
N90 M30              (Program end)
