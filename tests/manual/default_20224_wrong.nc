; TF5200 diagnosis, ID 20224 "'DEFAULT' must be programmed exclusively in NC-block.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251167883.html
; adapted: the page's ":" lines dropped.
; expect: error 20224
N10 G00 X0 Y0 Z0
N20 P1=5
N50 $SWITCH P1
N62 $DEFAULT G01 X100 F10000
N65 $ENDSWITCH
N1000 M30
