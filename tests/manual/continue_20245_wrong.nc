; TF5200 diagnosis, ID 20245 "'CONTINUE' must be programmed exclusively in NC-block.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251259275.html
; adapted: the page's ":" lines dropped.
; expect: error 20245
N10   G00 X0 Y0 Z0
N20   $FOR P1=1, 10, 2
N30        $IF P1 == 8
N40          $CONTINUE G01 X100 F10000
N50        $ENDIF
N100  $ENDFOR
N1000 M30
