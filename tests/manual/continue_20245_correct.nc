; TF5200 diagnosis, ID 20245 "'CONTINUE' must be programmed exclusively in NC-block.": the correct program ($FOR over 1 3 5 7 9, so P1 == 8 never holds and N35 never runs)
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251259275.html
; adapted: the page's ":" lines dropped.
; expect: end X=0 Y=0 Z=0
; expect: runs N1000 1
N10   G00 X0 Y0 Z0
N20   $FOR P1=1, 10, 2
N30        $IF P1 == 8
N35          G01 X100 F10000
N40          $CONTINUE
N50        $ENDIF
N100  $ENDFOR
N1000 M30
